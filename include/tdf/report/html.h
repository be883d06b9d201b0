#pragma once
/// Pieces shared by tdf's HTML reports (run pages, comparison pages, batch indexes): escaping,
/// links relative to the page, the page frame with its inline stylesheet, and the folder of
/// scripts the pages load (`report_assets/` beside the page).
///
/// Every page is self-contained in its folder: images are files beside the page referenced by
/// relative URLs, scripts are classic `<script src>` files in `report_assets/` (ES modules and
/// fetch() do not work from file:// in Chromium), nothing is fetched from the network. Copying
/// the folder elsewhere keeps the page working.
#include <tdf/core/config.h>

#include <string>

namespace tdf {

/// `text` with & < > " ' replaced by entities: safe as element content and as a quoted
/// attribute value.
std::string html_escape(const std::string& text);

/// The URL of `path` as seen from a page in `page_folder`: relative, '/'-separated, each segment
/// percent-encoded (RFC 3986 unreserved characters kept). Both are filesystem paths (absolute
/// or relative to the working directory).
std::string relative_url(const std::string& path, const std::string& page_folder);

/// JSON for a `<script>` block or an HTML attribute: `json.dump()` with '<', '>' and '&'
/// written as \u003c, \u003e, \u0026 (so "</script>" in a value cannot end the block).
std::string json_for_html(const Json& json);

/// "<!DOCTYPE html>...<body>" with the title, the shared stylesheet (inline) and `extra_head`.
std::string html_page_begin(const std::string& title, const std::string& extra_head = "");
/// The closing "</body></html>" with `scripts` (already HTML) before </body>.
std::string html_page_end(const std::string& scripts = "");

/// A number for a table: fixed 4 significant digits, "inf"/"nan" spelled out; JSON numbers
/// and strings are shown as they are.
std::string format_number(double value);
std::string format_json_value(const Json& value);

/// Standard RFC 4648 base64 of `bytes`.
std::string base64_encode(const std::string& bytes);

/// The name of the scripts folder beside each page.
inline constexpr const char* kReportAssetsFolder = "report_assets";

/// Writes `<page_folder>/report_assets/`: three.min.js, GLTFLoader.js, OrbitControls.js (three.js
/// r147, copied from the npm package that scripts/install-deps.sh installs into web/node_modules;
/// the environment variable TDF_WEB_MODULES names another node_modules folder) and tdf_viewer.js
/// and tdf_plot.js (built into tdf). Returns false, after a warning, when three.js is not installed: pages
/// still work and say so in place of the 3D view. Files already there with the same size are kept.
bool install_report_assets(const std::string& page_folder);

/// The node_modules folder install_report_assets copies from.
std::string web_modules_folder();

}  // namespace tdf
