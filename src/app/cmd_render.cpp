// `tdf render scene.json -o out/ [key=value ...]`: one multi-layer EXR per view.
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/progress.h>
#include <tdf/io/image_io.h>
#include <tdf/render/scene_assets.h>
#include <tdf/train/run_guard.h>
#include <tdf/scene/scene_file.h>

#include <filesystem>
#include <regex>
#include <set>

#include "commands.h"

namespace tdf::app {

namespace {

namespace fs = std::filesystem;

// Removes the view files of an earlier render into `folder` that this render will not rewrite
// (more views, other passes, or PNGs without --png), so the folder never mixes two renders.
void remove_stale_views(const std::string& folder, std::size_t views, const std::vector<Pass>& passes, bool png) {
    std::set<std::string> fresh;
    for (std::size_t k = 0; k < views; ++k) {
        fresh.insert(fmt::format("view_{:03d}.exr", k));
        if (png)
            for (const Pass pass : passes) fresh.insert(fmt::format("view_{:03d}_{}.png", k, pass_name(pass)));
    }
    static const std::regex view_file(R"(view_[0-9]+(\.exr|_[a-z_]+\.png))");
    std::vector<std::string> stale;
    for (const auto& entry : fs::directory_iterator(folder)) {
        const std::string file = entry.path().filename().string();
        if (entry.is_regular_file() && std::regex_match(file, view_file) && !fresh.count(file)) stale.push_back(file);
    }
    if (stale.empty()) return;
    std::sort(stale.begin(), stale.end());
    for (const std::string& file : stale) fs::remove(fs::path(folder) / file);
    log_info("removed {} file(s) of an earlier render in {} that this render does not write ({}{})", stale.size(), folder,
             stale.front(), stale.size() > 1 ? ", ..., " + stale.back() : "");
}

struct RenderOptions {
    std::string scene;
    std::string output;
    std::vector<std::string> overrides;
    bool png = false;
    int turntable = 0;
    std::string renderer;  // empty: the scene's
};

int run_render(const RenderOptions& o) {
    std::vector<std::string> overrides = o.overrides;
    if (o.turntable > 0) {
        // Turntable mode replaces the scene's views.
        for (const char* clear : {"views.orbit=[]", "views.random.count=0", "views.patches.count=0"})
            overrides.emplace_back(clear);
        overrides.push_back(fmt::format("views.turntable.count={}", o.turntable));
    }
    if (!o.renderer.empty()) overrides.push_back("renderer=\"" + o.renderer + "\"");
    const SceneDescription description = load_scene(o.scene, overrides);
    const auto assets = load_scene_assets(description);
    log_info("scene {}: seed {}, {}x{}, ssaa {}, {} shading, {} visibility, antialias {}",
             o.scene,
             description.seed,
             description.width,
             description.height,
             description.ssaa,
             description.shading,
             description.renderer,
             description.antialias ? "on" : "off");
    log_info("mesh {}: {} vertices, {} triangles; {} views",
             description.mesh,
             assets->mesh.positions.size(),
             assets->mesh.triangles.size(),
             assets->views.size());
    ensure_folder(o.output);
    // Lock the folder, clean what a killed run left, and clear views this render will not rewrite.
    const RunGuard guard(o.output, "render", "render");
    remove_stale_views(o.output, assets->views.size(), assets->passes, o.png);
    const std::string resolved = o.output + "/resolved_scene.json";
    write_text_atomically(resolved, description.to_json().dump(2) + "\n");
    log_verbose("resolved scene written to {}", resolved);

    const Renderer renderer(assets->mesh, *assets->scene, assets->material, assets->settings);
    ProgressReporter progress("render", assets->views.size());
    for (std::size_t k = 0; k < assets->views.size(); ++k) {
        const SceneView& view = assets->views[k];
        const Light light = scene_light(description, view, k);
        const Frame frame = renderer.render_ssaa(view.camera, view.ssaa, light, assets->passes);
        const std::string stem = fmt::format("{}/view_{:03d}", o.output, k);
        write_exr(stem + ".exr", frame.exr_layers());
        if (o.png)
            for (std::size_t p = 0; p < frame.passes.size(); ++p)
                write_png(fmt::format("{}_{}.png", stem, pass_name(frame.passes[p])),
                          preview_image(frame.passes[p], frame.images[p], frame.coverage));
        log_verbose("view {}: {}", k, view.label);
        progress.advance(1, view.label);
    }
    progress.finish();
    guard.complete({{"views", assets->views.size()}});
    log_info("wrote {} views to {}", assets->views.size(), o.output);
    return 0;
}

}  // namespace

Command register_render(CLI::App& root) {
    auto options = std::make_shared<RenderOptions>();
    Command command;
    CLI::App* app = root.add_subcommand(
        "render", "render the passes of a scene file's views to multi-layer EXRs (view_000.exr, ...)");
    app->add_option("scene", options->scene, "scene file (JSON, docs/scene-format.md)")->required();
    app->add_option(
        "overrides", options->overrides, "scene overrides key=value (dotted keys, e.g. image.width=256)");
    app->add_option("-o,--output", options->output, "output folder")->required();
    app->add_flag("--png", options->png, "also write 8-bit PNG previews view_NNN_<pass>.png")
        ->capture_default_str();
    app->add_option("--turntable",
                    options->turntable,
                    "replace the scene's views by N azimuths 360k/N at views.turntable.elevation (at most 10000)")
        ->check(CLI::Range(0, kMaxSceneViews))
        ->capture_default_str();
    app->add_option(
           "--renderer",
           options->renderer,
           "visibility: ray (Embree) or raster (nvdiffrast rules); overrides the scene's 'renderer' key "
           "(default ray)")
        ->check(CLI::IsMember({"ray", "raster"}));
    command.app = app;
    command.run = [options] { return run_render(*options); };
    return command;
}

}  // namespace tdf::app
