// `tdf atlas`: build (or keep) a UV atlas, optionally bake the albedo into it, report quality.
#include <tdf/atlas/bake.h>
#include <tdf/atlas/uv_atlas.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/mesh/mesh_writer.h>

#include <cstdio>
#include <filesystem>

#include "commands.h"

namespace tdf::app {

namespace {

struct AtlasCommandOptions {
    std::string input;
    std::string output;
    std::string report_path;
    std::string texture;
    std::string flattening = "lscm";
    bool bake_albedo = false;
    AtlasOptions atlas;
};

int run_atlas(const AtlasCommandOptions& o) {
    namespace fs = std::filesystem;
    const std::string ext = lower_extension(o.output);
    if (ext != ".obj" && ext != ".glb") throw_error("-o {}: the output must be .obj or .glb", o.output);
    AtlasOptions atlas_options = o.atlas;
    atlas_options.flattening = o.flattening == "arap" ? ChartFlattening::Arap : ChartFlattening::Lscm;
    TriangleMesh mesh = load_mesh(o.input);
    if (!o.texture.empty()) {
        mesh.albedo = read_image(o.texture);
        mesh.albedo_path = o.texture;
        if (!mesh.albedo.all_finite())
            throw_error("--texture {}: the texture contains NaN or infinite values", o.texture);
    }
    AtlasReport report;
    const TriangleMesh atlas = build_atlas(mesh, atlas_options, &report);

    Image albedo;
    if (o.bake_albedo) {
        if (mesh.has_colors())
            albedo = bake_vertex_colors(atlas, o.atlas.size);
        else if (!mesh.albedo.empty() && mesh.has_uvs())
            albedo = rebake_texture(mesh, mesh.albedo, atlas, o.atlas.size);
        else
            throw_error(
                "{}: --bake-albedo needs vertex colours or a UV-mapped texture, and the mesh has neither",
                o.input);
    } else if (!mesh.albedo.empty() && report.reunwrapped) {
        log_warning("{}: the texture does not follow the new UVs; add --bake-albedo to re-bake it", o.input);
    }

    if (ext == ".glb") {
        const Image* kept =
            (!o.bake_albedo && !report.reunwrapped && !mesh.albedo.empty()) ? &mesh.albedo : nullptr;
        write_glb(o.output, atlas, albedo.empty() ? kept : &albedo, nullptr);
    } else {
        ObjMaterial material;
        const fs::path out_path(o.output);
        if (!albedo.empty()) {
            material.albedo_map = out_path.stem().string() + "_albedo.png";
            write_png((out_path.parent_path() / material.albedo_map).string(), albedo, 8, Quantize::Round);
        } else if (!report.reunwrapped && !mesh.albedo_path.empty()) {
            // UVs unchanged: point at the original texture.
            const fs::path folder = out_path.parent_path().empty() ? fs::path(".") : out_path.parent_path();
            material.albedo_map = fs::relative(fs::absolute(mesh.albedo_path), fs::absolute(folder)).string();
        }
        write_obj(o.output, atlas, material);
    }
    std::fputs(format_atlas_report(report).c_str(), stdout);
    if (!o.report_path.empty()) write_text_atomically(o.report_path, atlas_report_json(report));
    if (report.overlaps > 0 || report.unmapped_faces > 0 || report.mirrored_charts > 0)
        log_warning(
            "{}: the UV layout has {} overlapping triangle pairs, {} unmapped faces, {} mirrored charts{}",
            o.input,
            report.overlaps,
            report.unmapped_faces,
            report.mirrored_charts,
            report.reunwrapped ? "" : " (the mesh's own UVs; --reunwrap replaces them)");
    return 0;
}

}  // namespace

Command register_atlas(CLI::App& root) {
    auto options = std::make_shared<AtlasCommandOptions>();
    Command command;
    CLI::App* app = root.add_subcommand("atlas",
                                        "build a UV atlas (charts flattened with CGAL, packed into one "
                                        "square texture), bake colours into it");
    app->add_option("mesh", options->input, "input mesh (.obj, .glb, .gltf or .ply)")->required();
    app->add_option("-o,--output", options->output, "output mesh (.obj with .mtl beside, or .glb)")
        ->required();
    app->add_option("--size", options->atlas.size, "atlas side in texels [16, 16384]")->capture_default_str();
    app->add_option("--gutter", options->atlas.gutter, "minimum empty texels between charts [0, 64]")
        ->capture_default_str();
    app->add_flag("--reunwrap",
                  options->atlas.reunwrap,
                  "replace the mesh's own UVs (a mesh without UVs is always unwrapped)");
    app->add_flag(
        "--bake-albedo",
        options->bake_albedo,
        "bake vertex colours (or re-bake the mesh's texture) into <output>_albedo.png (embedded for .glb)");
    app->add_option("--report", options->report_path, "also write the atlas report as JSON to this file");
    app->add_option(
        "--texture",
        options->texture,
        "albedo texture laid out by the input's UVs (default: the material's map_Kd), for --bake-albedo");
    app->add_option("--sharp-angle",
                    options->atlas.sharp_angle,
                    "degrees: dihedral angles above this always cut charts")
        ->capture_default_str();
    app->add_option("--cone-angle",
                    options->atlas.cone_angle,
                    "degrees: largest deviation of a face normal from its chart's mean normal")
        ->capture_default_str();
    app->add_option("--max-stretch",
                    options->atlas.max_stretch,
                    "per-chart L2 stretch bound; charts above it are split")
        ->capture_default_str();
    app->add_option(
           "--flattening",
           options->flattening,
           "chart flattening: lscm (conformal), or arap (LSCM, then ARAP for charts over the stretch bound)")
        ->check(CLI::IsMember({"lscm", "arap"}))
        ->capture_default_str();
    command.app = app;
    command.run = [options] { return run_atlas(*options); };
    return command;
}

}  // namespace tdf::app
