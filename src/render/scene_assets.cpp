#include <tdf/render/scene_assets.h>

#include <tdf/atlas/bake.h>
#include <tdf/atlas/uv_atlas.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/tactile/tactile_map.h>

#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/render/material_sampling.h>
#include <tdf/render/shading.h>

#include <cmath>

#include <filesystem>
#include <algorithm>

namespace tdf {

namespace {
Image read_checked(const std::string& path, const std::string& scene, const char* what) {
    if (!std::filesystem::exists(path)) throw_error("{}: {} '{}' does not exist", scene, what, path);
    Image image = read_image(path);
    if (!image.all_finite()) throw_error("{}: {} '{}' contains NaN or infinite values", scene, what, path);
    return image;
}

// Vertex-coloured meshes from image-to-3D tools have no UVs (spec 13.9), and other meshes' UVs
// may overlap or leave faces unmapped: give them `tdf atlas`'s default atlas so the tactile map
// (and the trained maps) have somewhere to go. A texture follows the surface onto the new atlas.
void reunwrap(SceneAssets& assets, const SceneDescription& d) {
    const bool had_uvs = assets.mesh.has_uvs();
    if (had_uvs)
        log_info("{}: replacing the mesh's UVs by a new atlas (uv.reunwrap)", d.mesh);
    else
        log_info("{}: the mesh has no UVs; unwrapping it with `tdf atlas`'s defaults (run `tdf atlas` to choose "
                 "the settings)", d.mesh);
    AtlasOptions options;
    options.reunwrap = true;
    AtlasReport report;
    TriangleMesh atlas = build_atlas(assets.mesh, options, &report);
    if (had_uvs && !assets.mesh.albedo.empty()) {
        const int size = std::max(options.size, std::max(assets.mesh.albedo.width(), assets.mesh.albedo.height()));
        atlas.albedo = rebake_texture(assets.mesh, assets.mesh.albedo, atlas, size);
        log_info("{}: albedo texture re-baked onto the new atlas ({}x{})", d.mesh, size, size);
    }
    assets.mesh = std::move(atlas);
    log_info("atlas: {} charts, {:.1f} % of texels used, {:.2f} s", report.chart_count, 100.0 * report.utilisation,
             report.seconds);
}

// Training lays the tactile map and learns its maps over the mesh's UVs: say what is wrong with
// them (the counts `tdf atlas` reports) instead of training silently on a broken layout.
void warn_about_uvs(const TriangleMesh& mesh, const SceneDescription& d) {
    const AtlasReport r = measure_atlas(mesh, 1024);
    std::string problems;
    const auto add = [&problems](std::size_t count, const std::string& what) {
        if (count > 0) problems += fmt::format("{}{} {}", problems.empty() ? "" : ", ", count, what);
    };
    add(r.overlaps, "overlapping triangle pairs (the faces share texels)");
    add(r.unmapped_faces, "unmapped faces (no UV area, or outside [0, 1])");
    add(r.mirrored_charts, fmt::format("mirrored charts ({} flipped triangles; shaded right with the handed tangents, "
                                       "but the tactile map runs mirrored there)", r.flipped_triangles));
    if (problems.empty()) return;
    log_warning("{}: the mesh's UVs have {}; set \"uv\": {{\"reunwrap\": true}} in the scene to train on a new atlas",
                d.mesh, problems);
}

}  // namespace

TactileLayoutTransform resolve_tactile_layout(const SceneDescription& d, const TriangleMesh& mesh, int map_width,
                                              float map_mm_per_pixel) {
    TactileLayoutTransform layout;
    const auto it = d.sections.find("tactile_layout");
    if (it == d.sections.end() || it->second.is_null()) return layout;
    const Json& section = it->second;
    if (!section.is_object()) throw_error("{}: tactile_layout must be an object", d.path);
    const std::string mode = section.value("mode", std::string("atlas"));
    if (mode == "atlas") return layout;
    if (mode != "physical")
        throw_error("{}: tactile_layout.mode must be one of atlas, physical, got '{}'", d.path, mode);
    const float mm_per_unit = section.value("mm_per_unit", 0.0f);
    if (!(mm_per_unit > 0) || !std::isfinite(mm_per_unit))
        throw_error("{}: tactile_layout.mode=physical needs tactile_layout.mm_per_unit > 0 (millimetres per mesh unit)",
                    d.path);
    const float given = section.value("mm_per_pixel", 0.0f);
    const float mm_per_pixel = given > 0 ? given : map_mm_per_pixel;
    if (!(mm_per_pixel > 0) || !std::isfinite(mm_per_pixel))
        throw_error("{}: tactile_layout.mode=physical needs the tactile map's millimetres per pixel: '{}' has no "
                    "tdf:mm_per_pixel metadata (make it with `tdf tactile`) and tactile_layout.mm_per_pixel is not set",
                    d.path, d.tactile_images.front());
    layout.uv_scale = physical_tactile_uv_scale(mesh, mm_per_unit, map_width, mm_per_pixel);
    log_info("tactile map at physical size: {:.1f} mm wide, repeated {:.2f} times across the atlas",
             double(map_width) * mm_per_pixel, layout.uv_scale);
    return layout;
}

std::unique_ptr<SceneAssets> load_scene_assets(const SceneDescription& d) {
    auto assets = std::make_unique<SceneAssets>();
    assets->description = d;
    MeshLoadOptions options;
    options.tangent_mode = d.tangents;
    options.load_textures = d.albedo_source == "mesh";
    if (!std::filesystem::exists(d.mesh)) throw_error("{}: mesh '{}' does not exist", d.path, d.mesh);
    assets->mesh = load_mesh(d.mesh, options);
    if (d.normalize) {
        // Recorded so the exported asset goes back to the file's coordinates (export_mesh).
        const Bounds3 b = compute_bounds(assets->mesh);
        const Vec3f e = b.extent();
        normalize_mesh(assets->mesh, d.normalize_bound);
        assets->normalization.center = b.center();
        assets->normalization.scale = 2.0f * d.normalize_bound / std::max(e.x, std::max(e.y, e.z));
    }
    const bool maps_need_uvs = !d.tactile_images.empty() || !d.label_map.empty();
    if (d.uv_reunwrap && (d.albedo_source == "image" || !d.label_map.empty()))
        throw_error("{}: uv.reunwrap replaces the mesh's UVs, which {} follows; re-bake it with `tdf atlas` instead",
                    d.path, d.albedo_source == "image" ? "albedo.image" : "label_map");
    if (d.uv_reunwrap || (maps_need_uvs && !assets->mesh.has_uvs() && d.albedo_source != "image"))
        reunwrap(*assets, d);
    else if (!d.tactile_images.empty() && assets->mesh.has_uvs())
        warn_about_uvs(assets->mesh, d);
    assets->scene = std::make_unique<EmbreeScene>(assets->mesh);

    using Source = SurfaceMaterial::AlbedoSource;
    SurfaceMaterial& m = assets->material;
    m.albedo_constant = d.albedo_color;
    if (d.albedo_source == "mesh") {
        if (!assets->mesh.albedo.empty() && assets->mesh.has_uvs()) {
            assets->albedo = MipTexture(assets->mesh.albedo);
            m.albedo_source = Source::Texture;
        } else if (assets->mesh.has_colors()) {
            m.albedo_source = Source::VertexColors;
        } else {
            log_warning("{}: mesh '{}' has no albedo texture or vertex colours; using grey 0.5", d.path, d.mesh);
            m.albedo_source = Source::Constant;
            m.albedo_constant = {0.5f, 0.5f, 0.5f};
        }
    } else if (d.albedo_source == "image") {
        assets->albedo = MipTexture(read_checked(d.albedo_image, d.path, "albedo image"));
        m.albedo_source = Source::Texture;
    } else if (d.albedo_source == "vertex_colors") {
        m.albedo_source = Source::VertexColors;
    } else {
        m.albedo_source = Source::Constant;
    }
    if (m.albedo_source == Source::Texture) m.albedo = &assets->albedo;
    if (!d.tactile_images.empty()) {
        const std::string& path = d.tactile_images.front();
        if (!std::filesystem::exists(path)) throw_error("{}: tactile image '{}' does not exist", d.path, path);
        const TactileMap map = load_tactile_map(path);
        assets->tactile = MipTexture(map.normals);
        m.tactile = &assets->tactile;
        m.tactile_layout = resolve_tactile_layout(d, assets->mesh, map.normals.width(), map.mm_per_pixel);
        // The map repeats over the atlas: one that does not tile shows its wrap at every repeat
        // (a line across the surface that no seam handling can remove).
        const SeamStatistics wrap = normal_map_wrap_statistics(map.normals);
        if (wrap.wrap_ratio_columns > kSeamLimit || wrap.wrap_ratio_rows > kSeamLimit)
            log_warning("{}: tactile map '{}' does not tile: the step across its wrap is {:.1f}x (columns) and {:.1f}x "
                        "(rows) the steps next to it, so every repeat shows a seam; `tdf tactile convert` makes "
                        "tileable maps",
                        d.path, path, wrap.wrap_ratio_columns, wrap.wrap_ratio_rows);
        if (d.tactile_images.size() > 1)
            log_info("{}: rendering the first of {} tactile images", d.path, d.tactile_images.size());
    }
    if (!d.label_map.empty()) {
        assets->label = MipTexture(read_checked(d.label_map, d.path, "label map"));
        m.label = &assets->label;
    }
    assets->settings.shading = parse_shading_mode(d.shading);
    assets->settings.color_space = parse_color_space(d.color_space);
    assets->settings.background = d.background;
    assets->settings.visibility = parse_visibility(d.renderer);
    assets->settings.antialias = d.antialias;
    for (const auto& name : d.passes) {
        try {
            assets->passes.push_back(parse_pass(name));
        } catch (const Error& e) {
            throw_error("{}: passes: {}", d.path, e.what());
        }
    }
    try {
        // Validates the material against the mesh (UVs, vertex colours) before any view renders.
        Renderer check(assets->mesh, *assets->scene, m, assets->settings);
    } catch (const Error& e) {
        throw_error("{}: {}", d.path, e.what());
    }
    assets->views = make_scene_views(d, assets->mesh);
    return assets;
}

Light scene_light(const SceneDescription& d, const SceneView& view, std::size_t index) {
    const LightSpec& spec = d.light;
    Light light;
    light.ambient = spec.ambient;
    if (spec.mode == "camera") {
        light.kind = Light::Kind::Directional;
        light.vector = view.has_angles
                           ? orbit_direction(view.elevation + spec.relative_elevation, view.azimuth + spec.relative_azimuth)
                           : view.camera.back;
    } else if (spec.mode == "directional") {
        light.kind = Light::Kind::Directional;
        light.vector = orbit_direction(spec.elevation, spec.azimuth);
    } else if (spec.mode == "point") {
        light.kind = Light::Kind::Point;
        light.vector = spec.position;
    } else {
        TDF_CHECK(spec.mode == "magic3d");
        Rng rng = Rng::stream(d.seed, 0x4c49474854ull + index);
        light.kind = Light::Kind::Point;
        light.vector = sample_magic3d_light(rng, view.camera.position);
    }
    return light;
}

TriangleMesh SceneAssets::export_mesh() const {
    TriangleMesh out = mesh;
    out.albedo = Image();
    const float inverse = 1.0f / normalization.scale;
    for (Vec3f& p : out.positions) p = p * inverse + normalization.center;
    return out;
}

}  // namespace tdf
