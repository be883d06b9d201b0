#include <tdf/render/scene_assets.h>

#include <tdf/atlas/uv_atlas.h>
#include <tdf/tactile/tactile_map.h>

#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/render/material_sampling.h>
#include <tdf/render/shading.h>

#include <cmath>

#include <filesystem>

namespace tdf {

namespace {
Image read_checked(const std::string& path, const std::string& scene, const char* what) {
    if (!std::filesystem::exists(path)) throw_error("{}: {} '{}' does not exist", scene, what, path);
    Image image = read_image(path);
    if (!image.all_finite()) throw_error("{}: {} '{}' contains NaN or infinite values", scene, what, path);
    return image;
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
    if (d.normalize) normalize_mesh(assets->mesh, d.normalize_bound);
    const bool maps_need_uvs = !d.tactile_images.empty() || !d.label_map.empty();
    if (maps_need_uvs && !assets->mesh.has_uvs() && d.albedo_source != "image") {
        // Vertex-coloured meshes from image-to-3D tools have no UVs (spec 13.9): give them an atlas
        // so the tactile map has somewhere to go.
        log_info("{}: the mesh has no UVs; unwrapping it with `tdf atlas`'s defaults (run `tdf atlas` to choose "
                 "the settings)", d.mesh);
        AtlasReport report;
        assets->mesh = build_atlas(assets->mesh, AtlasOptions{}, &report);
        log_info("atlas: {} charts, {:.1f} % of texels used, {:.2f} s", report.chart_count,
                 100.0 * report.utilisation, report.seconds);
    }
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
        if (d.tactile_images.size() > 1)
            log_info("{}: rendering the first of {} tactile images", d.path, d.tactile_images.size());
    }
    if (!d.label_map.empty()) {
        assets->label = MipTexture(read_checked(d.label_map, d.path, "label map"));
        m.label = &assets->label;
    }
    assets->settings.shading = parse_shading_mode(d.shading);
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

}  // namespace tdf
