#pragma once
/// The page a person opens to judge one `tdf optimize` run: `<name>_report.html` beside the
/// run's files. Input vs after-matching vs final turntables side by side, the exported maps, the
/// loss curves, the held-out quality numbers with what they mean, timings, the resolved
/// configuration, and an interactive 3D view of the exported .glb.
///
/// The writer takes plain data (paths, numbers, JSON) so any caller can fill it; the optimizer's
/// caller is collect_run_report() in tdf/train/run_report.h.
#include <tdf/core/config.h>
#include <tdf/report/viewer.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace tdf {

/// One row of turntable strips: the frames of each pass, in azimuth order.
struct TurntableStage {
    std::string label;                                       ///< e.g. "input"
    std::string description;                                 ///< one line under the label
    std::map<std::string, std::vector<std::string>> frames;  ///< pass name -> image paths
};

struct ReportImage {
    std::string caption;
    std::string path;
};

struct RunReport {
    std::string name;        ///< the run's file prefix, the page title
    std::string scene_path;  ///< shown in the header
    /// Columns of the turntable grid, in order; a stage without frames for a pass shows a gap.
    std::vector<std::string> turntable_passes{"albedo", "lambertian", "tactile_normal"};
    std::vector<TurntableStage> turntables;  ///< rows, e.g. input, after matching, final
    std::vector<ReportImage> maps;           ///< exported maps (PNG), shown at 256 px, linked
    /// The albedo against the input (issue 29): `_report.json`'s "colour" object (three numbers
    /// with their aims) and its spot strips (input | after matching | final), shown full size.
    Json colour = Json::object();
    std::vector<ReportImage> albedo_spots;
    /// Multi-part runs: `_report.json`'s "parts" array (docs/multi-part-textures.md), one row per
    /// part with its mask and material swatch (`mask`, `swatch`: files beside the page).
    Json parts = Json::array();
    /// Issue 24: `_report.json`'s "height_map" (the relief's scale) and "tactile_roundtrip" (a
    /// virtual GelSight against the input capture), and the touch previews: the capture's and the
    /// simulated touches' (side by side).
    Json height_map = Json::object(), tactile_roundtrip = Json::object();
    std::vector<ReportImage> touches;
    std::string loss_plot_svg;               ///< an SVG file inlined in the page; empty: none
    Json losses = Json::array();             ///< the `_losses.jsonl` objects, in order
    int init_iterations = 0;                 ///< end of the matching phase (a column of the loss table)
    /// Quality columns, e.g. {"after matching", {...}}, {"final", {...}}: the objects under
    /// "quality" in `_initialized_report.json` / `_report.json`. Known keys get their meaning.
    std::vector<std::pair<std::string, Json>> quality;
    Json timings = Json::object();   ///< `_report.json` without "quality": seconds, threads, seed
    Json config = Json::object();    ///< the resolved configuration
    std::string glb_path;            ///< the exported .glb; empty: no 3D view
    ViewerCamera camera;             ///< the 3D view's start camera
    std::vector<ReportImage> links;  ///< other files worth a link (OBJ, JSON, ...)
};

/// What a quality key means, in one sentence ("" for an unknown key).
std::string quality_meaning(const std::string& key);

/// Writes the page to `html_path` (atomically) and `report_assets/` + `<stem>_model.js` beside it.
/// Paths in `report` may be absolute or relative to the working directory; the page links them
/// relative to itself. Missing images are an error (tdf::Error naming the file).
void write_run_report(const std::string& html_path, const RunReport& report);

}  // namespace tdf
