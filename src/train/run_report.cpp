#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/render/texture.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/train/asset_export.h>
#include <tdf/train/run_report.h>

#include <chrono>
#include <filesystem>
#include <sstream>

namespace tdf {

namespace fs = std::filesystem;

namespace {

bool exists(const std::string& path) {
    std::error_code ec;
    return fs::is_regular_file(path, ec);
}

// The float EXR when the run wrote one (no quantisation), else the 8-bit PNG.
Image load_albedo(const std::string& stem) {
    return exists(stem + "_albedo.exr") ? read_image(stem + "_albedo.exr") : read_image(stem + "_albedo.png");
}

Image load_normals(const std::string& stem) {
    return exists(stem + "_tactile_normal.exr") ? read_image(stem + "_tactile_normal.exr")
                                                : load_tactile_map(stem + "_tactile_normal.png").normals;
}

const char* const kTurntablePasses[] = {"albedo", "lambertian", "tactile_normal", "shading_normal"};

TurntableStage stage_frames(const std::string& folder, const std::string& subfolder, int views,
                            std::string label, std::string description) {
    TurntableStage stage;
    stage.label = std::move(label);
    stage.description = std::move(description);
    for (const char* pass : kTurntablePasses)
        for (int k = 0; k < views; ++k) {
            const std::string path = fmt::format("{}/{}/{}_{:03d}.png", folder, subfolder, pass, k);
            if (exists(path)) stage.frames[pass].push_back(path);
        }
    return stage;
}

// The round trip's pictures, side by side at one scale: each part's input capture, then the
// touches that landed on it (tactile_roundtrip.h names the files).
void add_touch_images(RunReport& r, const std::string& folder) {
    const Json parts = r.tactile_roundtrip.value("parts", Json::array());
    const Json touch_parts = r.tactile_roundtrip.value("touch_parts", Json::array());
    if (parts.empty()) {
        const std::string capture = folder + "/touch/capture_gelsight.png";
        if (exists(capture)) r.touches.push_back({"input capture (the scene's tactile map)", capture});
    }
    for (const Json& part : parts) {
        const std::string name = part.value("name", ""), capture = folder + "/" + part.value("capture_preview", "");
        if (exists(capture)) r.touches.push_back({fmt::format("input capture of part {}", name), capture});
        for (std::size_t k = 0; k < touch_parts.size(); ++k) {
            const std::string touch = fmt::format("{}/touch/touch_{:03d}_gelsight.png", folder, k);
            if (touch_parts[k] == name && exists(touch))
                r.touches.push_back({fmt::format("virtual GelSight touch {} (part {})", k, name), touch});
        }
    }
    if (!parts.empty()) return;
    for (int k = 0; exists(fmt::format("{}/touch/touch_{:03d}_gelsight.png", folder, k)); ++k)
        r.touches.push_back({fmt::format("virtual GelSight touch {} of the exported asset", k),
                             fmt::format("{}/touch/touch_{:03d}_gelsight.png", folder, k)});
}

}  // namespace

RunReport collect_run_report(const std::string& folder, const std::string& name,
                             const std::string& scene_path, const TriangleMesh& mesh,
                             const RunConfig& config) {
    RunReport r;
    r.name = name;
    r.scene_path = scene_path;
    r.init_iterations = config.init_iterations;
    const std::string base = folder + "/" + name;
    const int views = config.turntable_views;
    const std::pair<const char*, const char*> stages[][2] = {
        {{"turntable_input", "input"}, {"the scene's own colour and tactile map", ""}},
        {{"turntable_initialized", "after matching"},
         {"the _initialized export (end of the matching phase)", ""}},
        {{"turntable", "final"}, {"the exported asset", ""}}};
    for (const auto& s : stages) {
        TurntableStage stage = stage_frames(folder, s[0].first, views, s[0].second, s[1].first);
        if (!stage.frames.empty()) r.turntables.push_back(std::move(stage));
    }
    for (const char* postfix : {"", "_initialized"})
        for (const char* map : {"_albedo.png", "_tactile_normal.png", "_height.png", "_ao.png"}) {
            const std::string path = base + postfix + map;
            if (exists(path)) r.maps.push_back({fs::path(path).filename().string(), path});
        }
    if (exists(base + "_loss_plot.svg")) r.loss_plot_svg = base + "_loss_plot.svg";
    if (exists(base + "_losses.jsonl")) {
        std::istringstream lines(read_text_file(base + "_losses.jsonl"));
        std::string line;
        while (std::getline(lines, line))
            if (!line.empty()) r.losses.push_back(parse_json(line, base + "_losses.jsonl"));
    }
    if (exists(base + "_initialized_report.json"))
        r.quality.push_back(
            {"after matching",
             load_json_file(base + "_initialized_report.json").value("quality", Json::object())});
    if (exists(base + "_report.json")) {
        Json report = load_json_file(base + "_report.json");
        r.quality.push_back({"final", report.value("quality", Json::object())});
        if (report.contains("colour")) {
            r.colour = report["colour"];
            for (const Json& spot : r.colour.value("spots", Json::array())) {
                const std::string path = folder + "/" + spot.value("file", "");
                if (exists(path))
                    r.albedo_spots.push_back(
                        {fmt::format("{} spot (input luminance {:.2f}): input | after matching | final",
                                     spot.value("name", ""), spot.value("input_luminance", 0.0)),
                         path});
            }
            report.erase("colour");
        }
        for (const char* key : {"height_map", "tactile_roundtrip"})
            if (report.contains(key)) {
                (std::string(key) == "height_map" ? r.height_map : r.tactile_roundtrip) = report[key];
                report.erase(key);
            }
        if (!r.tactile_roundtrip.empty()) add_touch_images(r, folder);
        if (report.contains("parts") && report["parts"].is_array()) r.parts = report["parts"];
        for (const char* key : {"quality", "parts", "part_segmentation"}) report.erase(key);
        r.timings = report;
    }
    if (exists(base + "_config.json")) r.config = load_json_file(base + "_config.json");
    if (exists(base + ".glb")) r.glb_path = base + ".glb";
    const TurntableFraming framing = turntable_framing(mesh);
    // The turntable's first view, so the 3D view starts where the strips start.
    r.camera =
        ViewerCamera::from_orbit(0.0f, 0.0f, framing.radius, framing.fovy_degrees, framing.target, 512, 512);
    const std::pair<const char*, const char*> links[] = {
        {".obj", "mesh + MTL naming both maps"},
        {".glb", "glTF 2.0 binary"},
        {"_config.json", "resolved configuration"},
        {"_report.json", "quality and timings"},
        {"_initialized_report.json", "quality after matching"},
        {"_losses.jsonl", "losses per iteration"}};
    for (const auto& [suffix, caption] : links)
        if (exists(base + suffix)) r.links.push_back({caption, base + suffix});
    return r;
}

void write_optimize_report(const std::string& folder, const std::string& name, const std::string& scene_path,
                           const SceneAssets& assets, const RunConfig& config) {
    const auto start = std::chrono::steady_clock::now();
    const int views = config.turntable_views, resolution = config.turntable_resolution;
    if (views > 0) {
        write_turntable(
            folder, "turntable_input", assets.mesh, *assets.scene, assets.material, views, resolution);
        const std::string stem = folder + "/" + name + "_initialized";
        if (exists(stem + "_albedo.png")) {
            const MipTexture albedo(load_albedo(stem)), tactile(load_normals(stem));
            SurfaceMaterial material;
            material.albedo_source = SurfaceMaterial::AlbedoSource::Texture;
            material.albedo = &albedo;
            material.tactile = &tactile;
            write_turntable(
                folder, "turntable_initialized", assets.mesh, *assets.scene, material, views, resolution);
        }
    }
    const std::string page = folder + "/" + name + "_report.html";
    // The 3D view shows the exported .glb, which is in the input file's coordinates (not the
    // normalised ones the turntables were rendered in): frame that mesh.
    write_run_report(page, collect_run_report(folder, name, scene_path, assets.export_mesh(), config));
    log_info("report: {} ({:.1f} s)",
             page,
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

}  // namespace tdf
