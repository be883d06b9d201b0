// `tdf tactile simulate`: a virtual GelSight pressed onto an exported asset (issue 24,
// docs/commands/tactile.md "simulate").
#include <tdf/core/atomic_file.h>
#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/render/virtual_gelsight.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/pipeline.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/tactile/touch_comparison.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "commands.h"

namespace tdf::app {

namespace {

namespace fs = std::filesystem;

struct SimulateArgs {
    std::string folder, at, out, capture, capture_area = "whole";
    int points = 0, pad_pixels = 0;
    float pitch_mm = 0;
    std::uint64_t seed = 0;
    CLI::App* app = nullptr;
};

Vec2f parse_uv(const std::string& text) {
    const auto comma = text.find(',');
    char* end = nullptr;
    const std::string u_text = text.substr(0, comma);
    const float u = std::strtof(u_text.c_str(), &end);
    const bool u_ok = comma != std::string::npos && end != u_text.c_str() && *end == '\0';
    const std::string v_text = comma == std::string::npos ? "" : text.substr(comma + 1);
    const float v = std::strtof(v_text.c_str(), &end);
    const bool v_ok = end != v_text.c_str() && *end == '\0';
    if (!u_ok || !v_ok || !std::isfinite(u) || !std::isfinite(v))
        throw_error("--at '{}': expected u,v (two numbers, e.g. 0.25,0.5)", text);
    return {u, v};
}

/// The sensor: --pad-pixels / --pitch-mm, else the capture the asset's relief came from (its
/// report's height_map.capture), else GelSight Mini's pitch over 240 pixels.
GelSightPad resolve_pad(const SimulateArgs& a, const ReliefAsset& asset) {
    GelSightPad pad;
    const std::string report = asset.obj_path.substr(0, asset.obj_path.size() - 4) + "_report.json";
    if (fs::exists(report)) {
        const Json j = parse_json(read_text_file(report), report);
        if (j.contains("height_map") && j["height_map"].contains("capture")) {
            const Json& c = j["height_map"]["capture"];
            pad.mm_per_pixel = c.value("mm_per_pixel", pad.mm_per_pixel);
            pad.width = pad.height = std::min(c.value("width", pad.width), c.value("height", pad.height));
        }
    }
    if (a.pad_pixels > 0) pad.width = pad.height = a.pad_pixels;
    if (a.pitch_mm > 0) pad.mm_per_pixel = a.pitch_mm;
    return pad;
}

int run_simulate(const SimulateArgs& a) {
    if (a.at.empty() == (a.points == 0)) throw_error("tdf tactile simulate: give either --at u,v or --points N");
    const std::unique_ptr<ReliefAsset> asset = load_relief_asset(a.folder);
    const GelSightPad pad = resolve_pad(a, *asset);
    std::vector<TouchPoint> points;
    if (!a.at.empty()) {
        const Vec2f uv = parse_uv(a.at);
        const std::optional<TouchPoint> p = touch_point_at_uv(asset->mesh, uv);
        if (!p) throw_error("--at {}: no face of {} covers that UV point (off the mesh)", a.at, asset->obj_path);
        points.push_back(*p);
    } else {
        points = random_touch_points(asset->mesh, a.points, a.seed);
    }
    // Every touch first, files after: a pad that does not fit leaves nothing behind.
    std::vector<SimulatedTouch> touches;
    for (const TouchPoint& p : points) touches.push_back(simulate_touch(*asset, p, pad));

    const std::string out = a.out.empty() ? (fs::path(a.folder) / "touch").string() : a.out;
    ensure_folder(out);
    Json list = Json::array();
    std::vector<ReliefMeasure> measures;
    for (std::size_t k = 0; k < touches.size(); ++k) {
        const std::string base = fmt::format("{}/touch_{:03d}", out, k);
        write_height_map(base + "_height.exr", touches[k].height);
        write_height_preview_png(base + "_height.png", touches[k].height);
        write_normal_map(base + "_normal.png", touches[k].normals, pad.mm_per_pixel, asset->obj_path, 16);
        write_png(base + "_gelsight.png", touches[k].preview, 8, Quantize::Round);
        measures.push_back(measure_relief(touches[k].height.height, pad.mm_per_pixel));
        const TouchPoint& p = points[k];
        list.push_back({{"uv", {p.uv.x, p.uv.y}},
                        {"position", {p.position.x, p.position.y, p.position.z}},
                        {"detail_tilt_degrees", measures.back().detail_tilt},
                        {"height_rms_mm", measures.back().height_rms_mm},
                        {"files", base + "_{height.exr,height.png,normal.png,gelsight.png}"}});
        log_info("touch {} at uv ({:.4f}, {:.4f}): detail tilt {:.2f} deg, detail height RMS {:.4f} mm -> {}_*.png", k,
                 p.uv.x, p.uv.y, measures.back().detail_tilt, measures.back().height_rms_mm, base);
    }
    Json summary = {{"asset", asset->obj_path},
                    {"pad", {{"width", pad.width}, {"height", pad.height}, {"mm_per_pixel", pad.mm_per_pixel}}},
                    {"mm_per_unit", asset->mm_per_unit},
                    {"touches", list}};
    if (!a.capture.empty()) {
        const TactileMap capture = load_tactile_map(a.capture);
        const float pitch = capture.mm_per_pixel > 0 ? capture.mm_per_pixel : pad.mm_per_pixel;
        const CaptureArea area = a.capture_area == "contact" ? CaptureArea::Contact : CaptureArea::Whole;
        const TouchRoundTrip r =
            compare_touches(measure_capture(capture.normals, pitch, std::min(pad.width, pad.height), area), measures);
        summary["tactile_roundtrip"] = r.to_json();
        log_info("against {}: tilt ratio {:.3f}, height RMS ratio {:.3f}, spectrum distance {:.3f}", a.capture,
                 r.tilt_ratio, r.height_rms_ratio, r.spectrum_distance);
    }
    write_text_atomically(out + "/simulate.json", summary.dump(2) + "\n");
    log_info("wrote {} touch(es) of a {}x{} px pad at {} mm per pixel into {}", touches.size(), pad.width, pad.height,
             pad.mm_per_pixel, out);
    return 0;
}

}  // namespace

Command register_tactile_simulate(CLI::App& tactile) {
    auto a = std::make_shared<SimulateArgs>();
    CLI::App* app = tactile.add_subcommand(
        "simulate", "virtual GelSight: press a sensor onto an exported asset, write what it would measure");
    app->add_option("asset_folder", a->folder, "output folder of tdf optimize (<name>.obj + <name>_height.exr)")
        ->required();
    app->add_option("--at", a->at, "press at this texture coordinate u,v (OBJ convention, v up)");
    app->add_option("--points", a->points, "press at N points drawn uniformly over the surface")
        ->check(CLI::Range(1, 10000));
    app->add_option("--seed", a->seed, "random seed of --points")->capture_default_str();
    app->add_option("--pad-pixels", a->pad_pixels, "pad side in pixels (0 = the capture's, from the run's report)")
        ->check(CLI::Range(0, 4096))
        ->capture_default_str();
    app->add_option("--pitch-mm", a->pitch_mm, "pixel pitch in mm (0 = the capture's, else GelSight Mini 0.085)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    app->add_option("--capture", a->capture,
                    "input capture (tactile normal map) to compare with: tilt, height RMS and spectrum");
    app->add_option("--capture-area", a->capture_area,
                    "what of --capture to compare with: whole (all of it, as the asset carries a scene's map) or "
                    "contact (its textured region, for a raw GelSight capture)")
        ->check(CLI::IsMember({"whole", "contact"}))
        ->capture_default_str();
    app->add_option("-o,--output", a->out, "output folder (default <asset_folder>/touch)");
    app->fallthrough();
    a->app = app;
    Command command;
    command.app = app;
    command.run = [a]() { return run_simulate(*a); };
    return command;
}

}  // namespace tdf::app
