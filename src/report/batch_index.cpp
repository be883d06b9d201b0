#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/report/batch_index.h>
#include <tdf/report/html.h>

#include <cmath>
#include <filesystem>
#include <set>

namespace tdf {

namespace fs = std::filesystem;

namespace {

// Click a header: sort by that column (again: reverse). Cells carry data-value (numbers) so the
// sort does not parse formatted text; empty values go last in both directions.
constexpr const char* kSortScript = R"js(<script>
(function () {
  'use strict';
  var tables = document.querySelectorAll('table.sortable');
  Array.prototype.forEach.call(tables, function (table) {
    var headers = table.querySelectorAll('thead th');
    Array.prototype.forEach.call(headers, function (th, column) {
      th.addEventListener('click', function () {
        var numeric = th.getAttribute('data-type') === 'number';
        var direction = th.getAttribute('data-sort') === 'asc' ? 'desc' : 'asc';
        Array.prototype.forEach.call(headers, function (h) { h.removeAttribute('data-sort'); });
        th.setAttribute('data-sort', direction);
        var body = table.tBodies[0];
        var rows = Array.prototype.slice.call(body.rows);
        var key = function (row) {
          var cell = row.cells[column];
          var v = cell.hasAttribute('data-value') ? cell.getAttribute('data-value') : cell.textContent.trim();
          if (v === '') return null;
          return numeric ? Number(v) : v.toLowerCase();
        };
        rows.sort(function (a, b) {
          var x = key(a), y = key(b);
          if (x === null && y === null) return 0;
          if (x === null) return 1;
          if (y === null) return -1;
          var order = x < y ? -1 : x > y ? 1 : 0;
          return direction === 'asc' ? order : -order;
        });
        rows.forEach(function (row) { body.appendChild(row); });
      });
    });
  });
})();
</script>
)js";

std::string numeric_cell(double value, bool known) {
    if (!known || !std::isfinite(value)) return "<td class=\"num\" data-value=\"\">-</td>";
    return fmt::format(
        "<td class=\"num\" data-value=\"{}\">{}</td>", value, html_escape(format_number(value)));
}

bool is_failure(const std::string& status) {
    return status == "failed" || status == "fail" || status == "error" || status == "timeout";
}

}  // namespace

void write_batch_index(const std::string& html_path, const std::string& title,
                       const std::vector<BatchRow>& rows) {
    const std::string folder = fs::path(html_path).parent_path().string();
    std::vector<std::string> measures;
    std::set<std::string> seen;
    for (const BatchRow& row : rows)
        for (const auto& [name, value] : row.quality)
            if (seen.insert(name).second) measures.push_back(name);
    std::size_t failures = 0;
    for (const BatchRow& row : rows) failures += is_failure(row.status) ? 1 : 0;

    std::string html = html_page_begin(title);
    html += fmt::format(
        "<h1>{}</h1>\n<p class=\"subtitle\">{} jobs, <span class=\"{}\">{} failed</span> &middot; "
        "click a column to sort</p>\n",
        html_escape(title),
        rows.size(),
        failures ? "fail" : "pass",
        failures);
    html +=
        "<table class=\"sortable\">\n<thead><tr><th data-type=\"text\">job</th><th "
        "data-type=\"text\">preview</th>"
        "<th data-type=\"text\">status</th><th data-type=\"number\" class=\"num\">wall time (s)</th>";
    for (const std::string& m : measures)
        html += fmt::format("<th data-type=\"number\" class=\"num\">{}</th>", html_escape(m));
    html += "<th data-type=\"text\">error</th></tr></thead>\n<tbody>\n";
    for (const BatchRow& row : rows) {
        std::error_code ec;
        const bool has_page = !row.page.empty() && fs::is_regular_file(row.page, ec);
        const std::string href = has_page ? html_escape(relative_url(row.page, folder)) : "";
        html += "<tr>";
        html += has_page ? fmt::format("<td><a href=\"{}\">{}</a></td>", href, html_escape(row.job))
                         : fmt::format("<td>{}</td>", html_escape(row.job));
        if (row.thumbnail.empty()) {
            html += "<td data-value=\"\"></td>";
        } else {
            if (!fs::is_regular_file(row.thumbnail, ec))
                throw_error("batch index: thumbnail '{}' of job '{}' does not exist", row.thumbnail, row.job);
            const std::string img = fmt::format("<img class=\"thumb\" src=\"{}\" alt=\"{} preview\">",
                                                html_escape(relative_url(row.thumbnail, folder)),
                                                html_escape(row.job));
            html += fmt::format("<td data-value=\"{}\">{}</td>",
                                html_escape(row.job),
                                has_page ? fmt::format("<a href=\"{}\">{}</a>", href, img) : img);
        }
        html += fmt::format(
            "<td class=\"{}\">{}</td>", is_failure(row.status) ? "fail" : "pass", html_escape(row.status));
        html += numeric_cell(row.wall_seconds, row.wall_seconds >= 0);
        for (const std::string& m : measures) {
            double value = 0;
            bool known = false;
            for (const auto& [name, v] : row.quality)
                if (name == m) value = v, known = true;
            html += numeric_cell(value, known);
        }
        html += fmt::format("<td class=\"error-line\">{}</td></tr>\n", html_escape(row.error));
    }
    html += "</tbody></table>\n";
    html += html_page_end(kSortScript);
    write_text_atomically(html_path, html);
}

}  // namespace tdf
