#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/render/frame.h>
#include <tdf/render/pass.h>
#include <tdf/report/compare_report.h>
#include <tdf/report/html.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

namespace tdf {

namespace fs = std::filesystem;

namespace {

const ExrLayer* find_layer(const std::vector<ExrLayer>& layers, const std::string& name) {
    for (const ExrLayer& l : layers)
        if (l.name == name) return &l;
    return nullptr;
}

bool is_pass_name(const std::string& name) {
    for (const PassInfo& info : all_passes())
        if (name == info.name) return true;
    return false;
}

// A displayable RGB image of one layer: tdf passes as `tdf render --png` shows them; anything
// else by its range (signed: v/2 + 1/2, beyond [0, 1]: min-max, else as it is).
Image layer_preview(const ExrLayer& layer, const Image* mask) {
    const Image& src = layer.image;
    if (is_pass_name(layer.name)) {
        Image coverage = mask ? *mask : Image(src.width(), src.height(), 1, 1.0f);
        if (coverage.channels() != 1) coverage = coverage.channel_range(0, 1);
        return preview_image(parse_pass(layer.name), src, coverage);
    }
    float lo = 0, hi = 1;
    if (!src.values().empty()) {
        const auto [mn, mx] = std::minmax_element(src.values().begin(), src.values().end());
        lo = *mn, hi = *mx;
    }
    const bool signed_values = lo < -1e-6f && lo >= -1.0001f && hi <= 1.0001f;
    const bool beyond = !signed_values && (lo < -1e-6f || hi > 1.0001f);
    Image out(src.width(), src.height(), 3);
    const int colour_channels = std::min(src.channels(), 3);
    for (int y = 0; y < src.height(); ++y)
        for (int x = 0; x < src.width(); ++x)
            for (int c = 0; c < 3; ++c) {
                float v = src.at(x, y, colour_channels == 1 ? 0 : std::min(c, colour_channels - 1));
                if (colour_channels == 2 && c == 2) v = 0;
                if (signed_values)
                    v = v * 0.5f + 0.5f;
                else if (beyond)
                    v = hi > lo ? (v - lo) / (hi - lo) : 0.0f;
                out.at(x, y, c) = std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f);
            }
    return out;
}

// Inferno-like ramp (matplotlib's inferno at 6 stops): perceptually ordered, black = no difference.
std::array<float, 3> heat_colour(float t) {
    static const float kStops[6][3] = {{0.000f, 0.000f, 0.016f},
                                       {0.259f, 0.039f, 0.408f},
                                       {0.576f, 0.149f, 0.404f},
                                       {0.867f, 0.318f, 0.227f},
                                       {0.988f, 0.647f, 0.039f},
                                       {0.988f, 1.000f, 0.643f}};
    t = std::clamp(std::isfinite(t) ? t : 1.0f, 0.0f, 1.0f) * 5.0f;
    const int i = std::min(int(t), 4);
    const float f = t - float(i);
    return {kStops[i][0] + f * (kStops[i + 1][0] - kStops[i][0]),
            kStops[i][1] + f * (kStops[i + 1][1] - kStops[i][1]),
            kStops[i][2] + f * (kStops[i + 1][2] - kStops[i][2])};
}

std::string sanitize(const std::string& text) {
    std::string out;
    for (const char c : text)
        out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
    return out.empty() ? "image" : out;
}

std::string stats_rows(const std::vector<ChannelStats>& channels) {
    std::string html;
    for (const ChannelStats& s : channels)
        html += fmt::format(
            "<tr><td><code>{}</code></td><td class=\"num\">{}</td><td class=\"num\">{}</td>"
            "<td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">({}, {})</td></tr>\n",
            html_escape(s.name),
            format_number(s.mean_error),
            format_number(s.rms_error),
            format_number(s.psnr),
            format_number(s.max_error),
            s.max_x,
            s.max_y);
    return html;
}

bool is_failure(const std::string& result) { return result != "pass"; }

}  // namespace

std::string report_files_folder(const std::string& html_path) {
    const fs::path p(html_path);
    return (p.parent_path() / (p.stem().string() + "_files")).string();
}

CompareFile compare_file_entry(const std::string& label, const std::string& a_path, const std::string& b_path,
                               const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b,
                               const CompareResult& overall, const CompareOptions& options,
                               const std::string& image_folder, const std::string& prefix) {
    CompareFile file;
    file.label = label;
    file.a_path = a_path;
    file.b_path = b_path;
    file.result = overall.passed ? "pass" : "fail";
    file.width = overall.width;
    file.height = overall.height;
    file.compared_pixels = overall.compared_pixels;
    file.failed_pixels = overall.failed_pixels;
    file.fail_percent = overall.fail_percent;
    file.overall = overall.overall;
    ensure_folder(image_folder);
    const ExrLayer* a_mask = find_layer(a, "mask");
    const ExrLayer* b_mask = find_layer(b, "mask");
    for (const ExrLayer& la : a) {
        const ExrLayer* lb = find_layer(b, la.name);
        if (!lb) continue;  // compare_layers already refused different channel sets
        ComparePass pass;
        pass.name = la.name.empty() ? "image" : la.name;
        // The verdict rule of the whole file applied to this pass; the mask rides along so that
        // --erode-mask excludes the same silhouette pixels.
        std::vector<ExrLayer> sa{la}, sb{*lb};
        if (options.erode_mask > 0 && la.name != "mask" && a_mask && b_mask)
            sa.push_back(*a_mask), sb.push_back(*b_mask);
        const CompareResult r = compare_layers(sa, sb, options, a_path, b_path);
        pass.passed = r.passed;
        pass.failed_pixels = r.failed_pixels;
        pass.fail_percent = r.fail_percent;
        for (const ChannelStats& s : r.channels)
            if (la.name.empty() || s.name.rfind(la.name + ".", 0) == 0) pass.channels.push_back(s);

        const std::string stem = fmt::format("{}/{}_{}", image_folder, prefix, sanitize(pass.name));
        const Image* mask_a = a_mask ? &a_mask->image : nullptr;
        const Image* mask_b = b_mask ? &b_mask->image : nullptr;
        pass.a_image = stem + "_a.png";
        pass.b_image = stem + "_b.png";
        pass.heatmap = stem + "_diff.png";
        write_png(pass.a_image, layer_preview(la, mask_a));
        write_png(pass.b_image, layer_preview(*lb, mask_b));
        const Image& ia = la.image;
        const Image& ib = lb->image;
        Image diff(ia.width(), ia.height(), 1);
        float largest = 0;
        for (int y = 0; y < ia.height(); ++y)
            for (int x = 0; x < ia.width(); ++x) {
                float d = 0;
                for (int c = 0; c < ia.channels(); ++c) {
                    const float e = std::fabs(ia.at(x, y, c) - ib.at(x, y, c));
                    d = std::max(d, std::isfinite(e) ? e : std::numeric_limits<float>::infinity());
                }
                diff.at(x, y, 0) = d;
                if (std::isfinite(d)) largest = std::max(largest, d);
            }
        // Scale to the pass's largest difference so structure shows even when it is tiny; the
        // page states the scale.
        pass.heat_scale = largest;
        Image heat(ia.width(), ia.height(), 3);
        for (int y = 0; y < ia.height(); ++y)
            for (int x = 0; x < ia.width(); ++x) {
                const auto colour = heat_colour(largest > 0 ? diff.at(x, y, 0) / largest : 0.0f);
                for (int c = 0; c < 3; ++c) heat.at(x, y, c) = colour[std::size_t(c)];
            }
        write_png(pass.heatmap, heat);
        file.passes.push_back(std::move(pass));
    }
    std::stable_sort(file.passes.begin(), file.passes.end(), [](const ComparePass& x, const ComparePass& y) {
        return !x.passed && y.passed;
    });
    return file;
}

CompareFile compare_file_problem(const std::string& label, const std::string& a_path,
                                 const std::string& b_path, const std::string& result,
                                 const std::string& message) {
    CompareFile file;
    file.label = label;
    file.a_path = a_path;
    file.b_path = b_path;
    file.result = result;
    file.message = message;
    return file;
}

void write_compare_report(const std::string& html_path, const CompareReport& report) {
    const std::string folder = fs::path(html_path).parent_path().string();
    std::vector<const CompareFile*> files;
    for (const CompareFile& f : report.files) files.push_back(&f);
    std::stable_sort(files.begin(), files.end(), [](const CompareFile* x, const CompareFile* y) {
        const bool fx = is_failure(x->result), fy = is_failure(y->result);
        if (fx != fy) return fx;
        return x->label < y->label;
    });
    std::size_t failed = 0;
    for (const CompareFile* f : files) failed += is_failure(f->result) ? 1 : 0;
    const CompareOptions& t = report.thresholds;

    std::string html = html_page_begin(report.title);
    html += fmt::format(
        "<h1>{}</h1>\n<p class=\"subtitle\">{} file{} compared, <span class=\"{}\">{} failed</span>"
        " &middot; a pixel fails when a channel differs by more than {}; a file fails when more than "
        "{} % of its pixels fail or any difference exceeds {}{}</p>\n",
        html_escape(report.title),
        files.size(),
        files.size() == 1 ? "" : "s",
        failed ? "fail" : "pass",
        failed,
        format_number(t.fail),
        format_number(t.failpercent),
        format_number(t.hardfail),
        t.erode_mask > 0 ? fmt::format("; pixels within {} of a silhouette are ignored", t.erode_mask)
                         : std::string());
    html +=
        "<table>\n<tr><th>file</th><th>result</th><th class=\"num\">failed pixels</th><th "
        "class=\"num\">PSNR</th>"
        "<th class=\"num\">max error</th></tr>\n";
    for (std::size_t i = 0; i < files.size(); ++i) {
        const CompareFile& f = *files[i];
        html += fmt::format(
            "<tr><td><a href=\"#file-{}\">{}</a></td><td class=\"{}\">{}</td><td class=\"num\">{}</td>"
            "<td class=\"num\">{}</td><td class=\"num\">{}</td></tr>\n",
            i,
            html_escape(f.label),
            is_failure(f.result) ? "fail" : "pass",
            html_escape(f.result),
            f.passes.empty() ? "-" : fmt::format("{} ({} %)", f.failed_pixels, format_number(f.fail_percent)),
            f.passes.empty() ? "-" : format_number(f.overall.psnr),
            f.passes.empty() ? "-" : format_number(f.overall.max_error));
    }
    html += "</table>\n";

    for (std::size_t i = 0; i < files.size(); ++i) {
        const CompareFile& f = *files[i];
        html += fmt::format("<h2 id=\"file-{}\">{} <span class=\"{}\">{}</span></h2>\n",
                            i,
                            html_escape(f.label),
                            is_failure(f.result) ? "fail" : "pass",
                            html_escape(f.result));
        html += fmt::format("<p class=\"subtitle\">A: <code>{}</code><br>B: <code>{}</code>{}</p>\n",
                            html_escape(f.a_path),
                            html_escape(f.b_path),
                            f.width > 0 ? fmt::format("<br>{} x {} pixels, {} compared, {} failed ({} %)",
                                                      f.width,
                                                      f.height,
                                                      f.compared_pixels,
                                                      f.failed_pixels,
                                                      format_number(f.fail_percent))
                                        : std::string());
        if (!f.message.empty())
            html += fmt::format("<p class=\"error-line\">{}</p>\n", html_escape(f.message));
        for (const ComparePass& p : f.passes) {
            html += fmt::format(
                "<div class=\"card\"><h3>{} <span class=\"{}\">{}</span> <span class=\"meaning\" "
                "style=\"font-weight:400\">{} pixels failed ({} %)</span></h3>\n",
                html_escape(p.name),
                p.passed ? "pass" : "fail",
                p.passed ? "pass" : "fail",
                p.failed_pixels,
                format_number(p.fail_percent));
            html += "<div class=\"compare-row\">\n";
            const std::pair<const std::string*, std::string> images[] = {
                {&p.a_image, "A"},
                {&p.b_image, "B"},
                {&p.heatmap, fmt::format("|A - B|: black 0, yellow {}", format_number(p.heat_scale))}};
            for (const auto& [path, caption] : images)
                html += fmt::format(
                    "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1} {2}\"></a><figcaption>{2}"
                    "</figcaption></figure>\n",
                    html_escape(relative_url(*path, folder)),
                    html_escape(p.name),
                    html_escape(caption));
            html +=
                "<div><table>\n<tr><th>channel</th><th class=\"num\">mean error</th><th "
                "class=\"num\">RMS</th>"
                "<th class=\"num\">PSNR</th><th class=\"num\">max error</th><th "
                "class=\"num\">at</th></tr>\n" +
                stats_rows(p.channels) +
                "</table>\n<p class=\"meaning\"><span class=\"legend\"></span> heatmap "
                "scale: black = equal, yellow = this pass's largest difference</p></div>\n";
            html += "</div></div>\n";
        }
    }
    html += html_page_end();
    write_text_atomically(html_path, html);
}

}  // namespace tdf
