#include <tdf/train/asset_export.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_writer.h>
#include <tdf/render/frame.h>
#include <tdf/render/renderer.h>
#include <tdf/render/texture.h>
#include <tdf/scene/embree_scene.h>

#include <fmt/format.h>

#include <cmath>

namespace tdf {

BakedMaps export_asset(const std::string& folder, const std::string& name, const std::string& postfix,
                       const TextureField& field, const TriangleMesh& mesh, const RunConfig& config,
                       const TriangleMesh* export_mesh) {
    BakedMaps maps = bake_field(field, mesh, config.texture_size, config.gutter);
    write_asset(folder, name, postfix, maps, export_mesh ? *export_mesh : mesh, config);
    return maps;
}

void write_asset(const std::string& folder, const std::string& name, const std::string& postfix,
                 const BakedMaps& maps, const TriangleMesh& mesh, const RunConfig& config) {
    const std::string stem = name + postfix;
    const std::string base = folder + "/" + stem;
    // Matches reference: 8-bit maps by truncation (spec 1.5 step 6, 13.20); EXRs keep floats.
    // The albedo is stored as it is rendered and trained (the input's own values, sRGB-encoded
    // for a texture): exactly what glTF's baseColorTexture and an OBJ's map_Kd hold.
    const std::string albedo_png = base + "_albedo.png", normal_png = base + "_tactile_normal.png";
    write_png(albedo_png, maps.albedo, 8, Quantize::Truncate);
    write_png(normal_png, encode_normal_map(maps.tactile_normal), 8, Quantize::Truncate);
    if (config.write_exr) {
        write_exr(base + "_albedo.exr", maps.albedo, ExrPixelType::Float);
        write_exr(base + "_tactile_normal.exr", maps.tactile_normal, ExrPixelType::Float);
    }
    ObjMaterial material;
    material.name = "defaultMat";
    material.albedo_map = stem + "_albedo.png";
    material.normal_map = stem + "_tactile_normal.png";
    write_obj(base + ".obj", mesh, material);
    if (config.write_glb) {
        // The GLB embeds the very bytes of the PNG files beside it.
        GlbMaps glb_maps;
        glb_maps.albedo_png = read_text_file(albedo_png);
        glb_maps.normal_png = read_text_file(normal_png);
        write_glb(base + ".glb", mesh, glb_maps);
    }
    log_info("exported {}.obj (+ .mtl{}, maps {}x{})", base, config.write_glb ? ", .glb" : "", maps.albedo.width(),
             maps.albedo.height());
}

TurntableFraming turntable_framing(const TriangleMesh& mesh) {
    // Frame the object whatever its units: a sphere around the box centre through the farthest
    // vertex fills the view.
    const Bounds3 bounds = compute_bounds(mesh);
    float extent = 0.0f;
    for (const Vec3f& p : mesh.positions) extent = std::max(extent, length(p - bounds.center()));
    TurntableFraming framing;
    framing.target = bounds.center();
    framing.radius = 1.05f * extent / std::sin(radians(framing.fovy_degrees) * 0.5f);
    return framing;
}

Camera turntable_camera(const TurntableFraming& framing, int k, int views, int resolution) {
    Camera camera = Camera::orbit(0.0f, 360.0f * float(k) / float(views), framing.radius, framing.fovy_degrees,
                                  resolution, resolution, framing.target);
    camera.near_plane = std::min(camera.near_plane, 0.01f * framing.radius);
    return camera;
}

std::vector<std::string> write_turntable(const std::string& folder, const TriangleMesh& mesh, const EmbreeScene& scene,
                                         const BakedMaps& maps, int views, int resolution) {
    if (views <= 0) return {};
    const MipTexture albedo(maps.albedo), tactile(maps.tactile_normal);
    SurfaceMaterial material;
    material.albedo_source = SurfaceMaterial::AlbedoSource::Texture;
    material.albedo = &albedo;
    material.tactile = &tactile;
    return write_turntable(folder, "turntable", mesh, scene, material, views, resolution);
}

std::vector<std::string> write_turntable(const std::string& folder, const std::string& subfolder,
                                         const TriangleMesh& mesh, const EmbreeScene& scene,
                                         const SurfaceMaterial& material, int views, int resolution) {
    std::vector<std::string> written;
    if (views <= 0) return written;
    RenderSettings settings;
    settings.shading = ShadingMode::Visualizer;
    const Renderer renderer(mesh, scene, material, settings);
    const TurntableFraming framing = turntable_framing(mesh);
    const std::vector<Pass> passes = {Pass::Albedo, Pass::Lambertian, Pass::TactileNormal, Pass::ShadingNormal};
    for (int k = 0; k < views; ++k) {
        const Camera camera = turntable_camera(framing, k, views, resolution);
        Light light;  // directional from the camera, visualizer ambient (spec 3.9)
        light.vector = camera.back;
        light.ambient = 0.1f;
        const Frame frame = renderer.render(camera, light, passes);
        for (std::size_t p = 0; p < passes.size(); ++p) {
            const std::string path = fmt::format("{}/{}/{}_{:03d}.png", folder, subfolder, pass_name(passes[p]), k);
            write_png(path, preview_image(passes[p], frame.images[p], frame.coverage), 8, Quantize::Truncate);
            written.push_back(path);
        }
    }
    return written;
}

}  // namespace tdf
