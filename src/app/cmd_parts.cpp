// `tdf parts`: run a multi-part scene's segmentation alone and write what the optimizer would
// use (label map, per-part masks, per-face labels, the composed tactile target, a report), so
// the parts can be checked before a long optimize.
#include <tdf/atlas/uv_atlas.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/parts/part_segmentation.h>
#include <tdf/parts/part_target.h>
#include <tdf/render/scene_assets.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/train/texture_bake.h>
#include <tdf/train/trainer.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "commands.h"

namespace tdf::app {

namespace {

struct PartsCommandOptions {
    std::string scene_path;
    std::vector<std::string> overrides;
    std::string output_dir;
    std::string name;
    int size = 1024;
    int gutter = 8;
    float band = kDefaultPartBand;
    bool target = true;
    std::string work_folder;
};

int run_parts(const PartsCommandOptions& o) {
    namespace fs = std::filesystem;
    const SceneDescription description = load_scene(o.scene_path, o.overrides);
    if (!description.parts.enabled())
        throw_error("{}: the scene has no 'parts' section (docs/multi-part-textures.md)", o.scene_path);
    const std::string name =
        o.name.empty() ? fs::absolute(o.scene_path).parent_path().filename().string() : o.name;
    ensure_folder(o.output_dir);
    const std::string base = o.output_dir + "/" + name;
    const auto assets = load_scene_assets(description);
    const TriangleMesh& mesh = assets->mesh;
    TriangleMesh atlas;
    if (!mesh.has_uvs()) {
        AtlasOptions atlas_options;
        atlas_options.size = o.size;
        atlas = build_atlas(mesh, atlas_options);
        log_info("{}: the mesh has no UVs; built an atlas ({} faces)", o.scene_path, atlas.triangles.size());
    }
    PartSegmentationInput input;
    input.mesh = &mesh;
    input.atlas = mesh.has_uvs() ? &mesh : &atlas;
    input.material = &assets->material;
    input.size = o.size;
    input.seed = description.seed;
    input.where = o.scene_path + ": parts";
    input.work_folder = o.work_folder;
    const PartSegmentation seg = segment_parts(description.parts, input);

    Json report = seg.report(description.parts);
    report["scene"] = o.scene_path;
    report["legend"] = write_part_maps(base, seg.texel_part, seg.size, seg.part_names, o.gutter);
    std::string faces = "# tdf parts: one part name per triangle (usable as parts.source kind face_labels)\n";
    for (int p : seg.face_part) faces += seg.part_names[std::size_t(p)] + "\n";
    write_text_atomically(base + "_face_labels.txt", faces);

    if (o.target) {
        const auto start = std::chrono::steady_clock::now();
        const ScenePartMaps laid = lay_scene_part_maps(description.parts, *input.atlas, seg.size, o.scene_path);
        const std::vector<Image>& layers = laid.layers;
        const Image target = compose_part_target(seg.texel_part, seg.size, layers, o.band, o.gutter);
        write_atomically(base + "_tactile_target.png", [&](const std::string& tmp) {
            write_png(tmp, encode_normal_map(target), 8, Quantize::Truncate);
        });
        const PartBoundaryMeasure m = measure_part_boundary(target, seg.texel_part, seg.size, layers, o.band);
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        Json scales = Json::array();
        for (float scale : laid.uv_scales) scales.push_back(scale);
        report["target"] = {{"band_width_texels", o.band},
                            {"uv_scale", scales},
                            {"bleed_texels", m.bleed_texels},
                            {"boundary_step_degrees", m.boundary_step_degrees},
                            {"hard_cut_step_degrees", m.hard_step_degrees},
                            {"step_ratio", m.step_ratio},
                            {"band_detail_ratio", m.band_detail_ratio},
                            {"interior_step_degrees", m.interior_step_degrees},
                            {"boundary_pairs", m.boundary_pairs},
                            {"seconds", seconds}};
        std::printf(
            "target: %s_tactile_target.png; at part boundaries: bleed %.1f texels, step %.2f deg (a hard "
            "cut: "
            "%.2f deg), relief strength in the band %.2f of the parts'\n",
            name.c_str(),
            m.bleed_texels,
            m.boundary_step_degrees,
            m.hard_step_degrees,
            m.band_detail_ratio);
    }
    write_text_atomically(base + "_parts.json", report.dump(2) + "\n");

    std::printf("parts of %s (source %s, %dx%d texels, %.2f s):\n",
                o.scene_path.c_str(),
                description.parts.source.kind.c_str(),
                seg.size,
                seg.size,
                seg.seconds);
    for (std::size_t p = 0; p < seg.part_count(); ++p) {
        const Vec3f c = part_colour(int(p));
        std::printf("  %zu %-16s %6.2f %% of the surface  label colour #%02x%02x%02x\n",
                    p,
                    seg.part_names[p].c_str(),
                    100.0 * seg.part_fraction[p],
                    int(c.x * 255),
                    int(c.y * 255),
                    int(c.z * 255));
    }
    std::printf("regions found by the source:\n");
    for (const PartRegion& r : seg.regions) {
        std::printf("  %-12s -> %-16s %6.2f %%",
                    r.name.c_str(),
                    seg.part_names[std::size_t(r.part)].c_str(),
                    100.0 * r.fraction);
        if (r.has_colour)
            std::printf("  mean colour #%02x%02x%02x",
                        int(std::lround(r.rgb.x * 255)),
                        int(std::lround(r.rgb.y * 255)),
                        int(std::lround(r.rgb.z * 255)));
        std::printf("\n");
    }
    std::printf(
        "wrote %s_label_map.png, %s_label_legend.json, %s_mask_<part>.png, %s_face_labels.txt, "
        "%s_parts.json\n",
        base.c_str(),
        name.c_str(),
        name.c_str(),
        name.c_str(),
        name.c_str());
    return 0;
}

}  // namespace

Command register_parts(CLI::App& root) {
    auto options = std::make_shared<PartsCommandOptions>();
    Command command;
    CLI::App* app = root.add_subcommand(
        "parts", "segment a multi-part scene into its parts and write the label map, masks and report");
    app->add_option("scene", options->scene_path, "scene file (JSON) with a 'parts' section")
        ->required()
        ->check(CLI::ExistingFile);
    app->add_option("overrides", options->overrides, "scene overrides key=value (e.g. parts.source.k=3)");
    app->add_option("-o,--output", options->output_dir, "output folder")->required();
    app->add_option("--name", options->name, "file name prefix (default: the scene's folder name)");
    app->add_option(
           "--size", options->size, "label raster side in texels (the optimizer's texture size) [16, 16384]")
        ->capture_default_str();
    app->add_option("--gutter", options->gutter, "texels the labels grow into the empty atlas around charts")
        ->capture_default_str()
        ->check(CLI::Range(0, 64));
    app->add_option(
           "--band",
           options->band,
           "texels over which two parts' tactile maps cross-fade [0, 1.5] (bleed stays within 2 texels)")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1.5));
    app->add_flag("!--no-target", options->target, "do not compose and write the multi-part tactile target");
    app->add_option(
        "--work-folder", options->work_folder, "external source: parent of the call folder (default: temp)");
    command.app = app;
    command.run = [options] { return run_parts(*options); };
    return command;
}

}  // namespace tdf::app
