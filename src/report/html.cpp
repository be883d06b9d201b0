#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/report/html.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace tdf {

namespace fs = std::filesystem;

// Generated at configure time from src/report/assets/ (see src/CMakeLists.txt).
extern const char* const kEmbeddedViewerJs;
extern const char* const kEmbeddedPlotJs;

namespace {

// Light page, dense tables, image strips that scroll sideways instead of shrinking to nothing.
constexpr const char* kStylesheet = R"css(
:root { --fg: #1d2329; --muted: #5f6b76; --line: #d5dbe1; --bg: #f6f7f9; --card: #ffffff;
        --pass: #1f7a3a; --fail: #b3261e; --warn: #9a6700; }
* { box-sizing: border-box; }
body { margin: 0; padding: 20px 28px 40px; font: 14px/1.45 system-ui, -apple-system, "Segoe UI", sans-serif;
       color: var(--fg); background: var(--bg); }
h1 { font-size: 22px; margin: 0 0 4px; }
h2 { font-size: 17px; margin: 28px 0 10px; padding-bottom: 4px; border-bottom: 1px solid var(--line); }
h3 { font-size: 15px; margin: 16px 0 8px; }
a { color: #0b57d0; }
.subtitle { color: var(--muted); margin: 0 0 16px; }
.card { background: var(--card); border: 1px solid var(--line); border-radius: 6px; padding: 12px 14px; margin: 10px 0; }
table { border-collapse: collapse; background: var(--card); }
th, td { border: 1px solid var(--line); padding: 4px 8px; text-align: left; vertical-align: top; }
th { background: #eef1f4; font-weight: 600; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
.meaning { color: var(--muted); max-width: 640px; }
.pass { color: var(--pass); font-weight: 600; }
.fail { color: var(--fail); font-weight: 600; }
.warn { color: var(--warn); font-weight: 600; }
.turntable { display: grid; grid-template-columns: 170px repeat(var(--frames), minmax(40px, 150px)); gap: 4px; align-items: start; }
.turntable img { width: 100%; aspect-ratio: 1; object-fit: contain; background: #fff; border: 1px solid var(--line); display: block; }
.turntable .label { font-weight: 600; padding: 4px 8px 0 0; }
.turntable .label .meaning { font-weight: 400; font-size: 12px; }
.figures { display: flex; flex-wrap: wrap; gap: 12px; }
figure { margin: 0; }
figure img { display: block; width: 256px; height: 256px; object-fit: contain; background: #fff; border: 1px solid var(--line); }
figcaption { color: var(--muted); font-size: 12px; margin-top: 2px; max-width: 256px; word-break: break-all; }
pre { background: var(--card); border: 1px solid var(--line); padding: 10px; overflow: auto; max-height: 480px; font-size: 12px; }
details summary { cursor: pointer; font-weight: 600; }
.tdf-viewer { display: flex; gap: 16px; align-items: flex-start; flex-wrap: wrap; }
.tdf-viewer canvas { width: 512px; height: 512px; outline: 1px solid var(--line); border-radius: 4px; background: #30343a; touch-action: none; }
.tdf-viewer .controls { display: grid; grid-template-columns: auto 180px; gap: 6px 10px; align-items: center; }
.tdf-viewer-status { color: var(--muted); grid-column: 1 / span 2; max-width: 320px; }
.tdf-viewer[data-state=error] .tdf-viewer-status, .tdf-viewer[data-state=unavailable] .tdf-viewer-status { color: var(--fail); }
.tdf-plot canvas { width: 900px; max-width: 100%; height: auto; border: 1px solid var(--line); background: #fff; }
.tdf-plot-legend { display: flex; flex-wrap: wrap; gap: 4px 14px; margin: 6px 0; font-size: 13px; }
.tdf-plot-legend .swatch { display: inline-block; width: 18px; height: 3px; vertical-align: middle; margin: 0 4px; }
.tdf-plot-readout { color: var(--muted); font-size: 12px; min-height: 1.4em; font-variant-numeric: tabular-nums; }
.loss-plot svg { max-width: 100%; height: auto; background: #fff; border: 1px solid var(--line); }
table.sortable th { cursor: pointer; user-select: none; white-space: nowrap; }
table.sortable th[data-sort=asc]::after { content: " \25B2"; }
table.sortable th[data-sort=desc]::after { content: " \25BC"; }
img.thumb { width: 96px; height: 96px; object-fit: contain; background: #fff; border: 1px solid var(--line); display: block; }
.error-line { font-family: ui-monospace, monospace; font-size: 12px; color: var(--fail); max-width: 520px; }
.compare-row { display: flex; gap: 12px; flex-wrap: wrap; align-items: flex-start; }
.compare-row figure img { image-rendering: pixelated; }
figure img.strip { width: auto; height: auto; max-width: 100%; image-rendering: pixelated; }
.legend { display: inline-block; width: 160px; height: 10px; vertical-align: middle; border: 1px solid var(--line);
          background: linear-gradient(to right, #000004, #420a68, #932667, #dd513a, #fca50a, #fcffa4); }
)css";

bool unreserved(unsigned char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
           c == '.' || c == '_' || c == '~';
}

}  // namespace

std::string html_escape(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            case '\'':
                out += "&#39;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string relative_url(const std::string& path, const std::string& page_folder) {
    const fs::path target = fs::absolute(path).lexically_normal();
    const fs::path base = fs::absolute(page_folder.empty() ? "." : page_folder).lexically_normal();
    fs::path relative = target.lexically_relative(base);
    if (relative.empty()) relative = target;
    std::string url;
    bool first = true;
    for (const fs::path& part : relative) {
        const std::string segment = part.string();
        if (segment.empty() || segment == "/") continue;
        if (!first) url += '/';
        first = false;
        for (const unsigned char c : segment) {
            if (unreserved(c))
                url += char(c);
            else
                url += fmt::format("%{:02X}", unsigned(c));
        }
    }
    return url;
}

std::string json_for_html(const Json& json) {
    const std::string text = json.dump(-1, ' ', false, Json::error_handler_t::replace);
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
        if (c == '<')
            out += "\\u003c";
        else if (c == '>')
            out += "\\u003e";
        else if (c == '&')
            out += "\\u0026";
        else if (c == '\'')
            out += "\\u0027";
        else
            out += c;
    }
    return out;
}

std::string html_page_begin(const std::string& title, const std::string& extra_head) {
    return fmt::format(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        "<meta name=\"generator\" "
        "content=\"tdf\">\n<title>{}</title>\n<style>{}</style>\n{}</head>\n<body>\n",
        html_escape(title),
        kStylesheet,
        extra_head);
}

std::string html_page_end(const std::string& scripts) { return scripts + "</body>\n</html>\n"; }

std::string format_number(double value) {
    if (std::isnan(value)) return "nan";
    if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
    if (value == std::floor(value) && std::fabs(value) < 1e9) return fmt::format("{:.0f}", value);
    return fmt::format("{:.4g}", value);
}

std::string format_json_value(const Json& value) {
    if (value.is_number()) return format_number(value.get<double>());
    if (value.is_string()) return value.get<std::string>();
    if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
    if (value.is_null()) return "-";
    return value.dump();
}

std::string base64_encode(const std::string& bytes) {
    static const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const unsigned v = (unsigned(static_cast<unsigned char>(bytes[i])) << 16) |
                           (unsigned(static_cast<unsigned char>(bytes[i + 1])) << 8) |
                           unsigned(static_cast<unsigned char>(bytes[i + 2]));
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += kAlphabet[(v >> 6) & 63];
        out += kAlphabet[v & 63];
    }
    const std::size_t rest = bytes.size() - i;
    if (rest > 0) {
        unsigned v = unsigned(static_cast<unsigned char>(bytes[i])) << 16;
        if (rest == 2) v |= unsigned(static_cast<unsigned char>(bytes[i + 1])) << 8;
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += rest == 2 ? kAlphabet[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

std::string web_modules_folder() {
    if (const char* env = std::getenv("TDF_WEB_MODULES"); env && *env) return env;
    return TDF_WEB_MODULES_DIR;
}

bool install_report_assets(const std::string& page_folder) {
    const fs::path assets = fs::path(page_folder.empty() ? "." : page_folder) / kReportAssetsFolder;
    ensure_folder(assets.string());
    write_text_atomically((assets / "tdf_viewer.js").string(), kEmbeddedViewerJs);
    write_text_atomically((assets / "tdf_plot.js").string(), kEmbeddedPlotJs);
    const fs::path three = fs::path(web_modules_folder()) / "three";
    const std::pair<const char*, const char*> files[] = {
        {"build/three.min.js", "three.min.js"},
        {"examples/js/loaders/GLTFLoader.js", "GLTFLoader.js"},
        {"examples/js/controls/OrbitControls.js", "OrbitControls.js"}};
    for (const auto& [from, to] : files) {
        const fs::path source = three / from;
        std::error_code ec;
        if (!fs::is_regular_file(source, ec)) {
            log_warning(
                "report: {} not found, so the page's 3D view is off (run scripts/install-deps.sh, or set "
                "TDF_WEB_MODULES to a node_modules folder with three@0.147.0)",
                source.string());
            return false;
        }
        const fs::path target = assets / to;
        if (fs::is_regular_file(target, ec) && fs::file_size(target, ec) == fs::file_size(source, ec))
            continue;
        write_text_atomically(target.string(), read_text_file(source.string()));
    }
    return true;
}

}  // namespace tdf
