#include <tdf/train/asset_export.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_writer.h>
#include <tdf/render/frame.h>
#include <tdf/render/renderer.h>
#include <tdf/render/texture.h>
#include <tdf/scene/embree_scene.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/train/asset_height.h>

#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <vector>

namespace tdf {

BakedMaps export_asset(const std::string& folder, const std::string& name, const std::string& postfix,
                       const TextureField& field, const TriangleMesh& mesh, const RunConfig& config,
                       const TriangleMesh* export_mesh) {
    BakedMaps maps = bake_field(field, mesh, config.texture_size, config.gutter);
    write_asset(folder, name, postfix, maps, export_mesh ? *export_mesh : mesh, config);
    return maps;
}

namespace {

/// The normals as the 8-bit PNG written by write_asset decodes them.
Image decoded_png_normals(const Image& normals) {
    Image unit = encode_normal_map(normals);
    for (float& v : unit.values()) v = v * 2.0f - 1.0f;
    return quantized_normals(unit, 8);
}

}  // namespace

Json write_asset(const std::string& folder, const std::string& name, const std::string& postfix,
                 const BakedMaps& maps, const TriangleMesh& mesh, const RunConfig& config,
                 const FaceMaterials& parts, const ExportScale* height_scale) {
    const std::string stem = name + postfix;
    const std::string base = folder + "/" + stem;
    // Matches reference: 8-bit maps by truncation (spec 1.5 step 6, 13.20); EXRs keep floats.
    // The albedo is stored as it is rendered and trained (the input's own values, sRGB-encoded
    // for a texture): exactly what glTF's baseColorTexture and an OBJ's map_Kd hold.
    const std::string albedo_png = base + "_albedo.png", normal_png = base + "_tactile_normal.png";
    ObjMaterial material;
    material.name = "defaultMat";
    material.albedo_map = stem + "_albedo.png";
    material.normal_map = stem + "_tactile_normal.png";
    // The map files are independent, and libpng's deflate runs on one thread: written side by side
    // they keep both cores busy (each file still written atomically). The height solve, parallel
    // itself and the export's memory peak (docs/measurements.md, 4096^2), runs after them.
    std::vector<std::function<void()>> writes = {
        [&] { write_png(albedo_png, maps.albedo, 8, Quantize::Truncate); },
        [&] { write_png(normal_png, encode_normal_map(maps.tactile_normal), 8, Quantize::Truncate); }};
    if (config.write_exr) {
        writes.push_back([&] { write_exr(base + "_albedo.exr", maps.albedo, ExrPixelType::Float); });
        writes.push_back([&] { write_exr(base + "_tactile_normal.exr", maps.tactile_normal, ExrPixelType::Float); });
    }
    parallel_tasks(writes);
    Json height_json;
    bool wrote_occlusion = false;
    if (height_scale && height_scale->mm_per_texel > 0) {
        const ExportedHeight height =
            export_surface_height(decoded_png_normals(maps.tactile_normal), *height_scale, mesh, maps.raster,
                                  config.height_metric, stem + "_tactile_normal.png");
        write_exported_height(base, height);
        wrote_occlusion = !height.occlusion.empty();
        height_json = exported_height_json(height, *height_scale, stem + "_height.png", stem + "_height.exr");
        if (height_scale->mm_per_unit > 0) material.height_map = stem + "_height.png";
        material.height_base = double(height.min_mm) / double(height_scale->mm_per_unit);
        material.height_gain = double(height.max_mm - height.min_mm) / double(height_scale->mm_per_unit);
        log_info("height map {}_height.exr: {:.4g} .. {:.4g} mm at {:.4g} mm per texel{}; normals recomputed from it: "
                 "mean cosine {:.5f}",
                 base, height.min_mm, height.max_mm, height_scale->mm_per_texel,
                 height_scale->assumed ? " (capture pixel size unknown: GelSight Mini's assumed)" : "",
                 height.mean_cosine);
        if (height.mean_cosine < kHeightConsistencyLimit)
            log_warning("{}: the height map reproduces the normal map only to a mean cosine of {:.4f} (limit {})",
                        normal_png, height.mean_cosine, kHeightConsistencyLimit);
    }
    write_obj(base + ".obj", mesh, material, parts);
    if (config.write_glb) {
        // The GLB embeds the very bytes of the PNG files beside it.
        GlbMaps glb_maps;
        glb_maps.albedo_png = read_text_file(albedo_png);
        glb_maps.normal_png = read_text_file(normal_png);
        if (!height_json.is_null()) {
            glb_maps.height_png = read_text_file(base + "_height.png");
            glb_maps.height_extras = height_json;
            if (wrote_occlusion) glb_maps.occlusion_png = read_text_file(base + "_ao.png");
        }
        write_glb(base + ".glb", mesh, glb_maps, parts);
    }
    log_info("exported {}.obj (+ .mtl{}, maps {}x{})", base, config.write_glb ? ", .glb" : "", maps.albedo.width(),
             maps.albedo.height());
    return height_json;
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
        std::vector<std::string> paths(passes.size());
        for (std::size_t p = 0; p < passes.size(); ++p)
            paths[p] = fmt::format("{}/{}/{}_{:03d}.png", folder, subfolder, pass_name(passes[p]), k);
        // One file per task: libpng encodes a file on one thread, and the render above is parallel.
        parallel_for(passes.size(), 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p)
                write_png(paths[p], preview_image(passes[p], frame.images[p], frame.coverage), 8, Quantize::Truncate);
        });
        written.insert(written.end(), paths.begin(), paths.end());
    }
    return written;
}

}  // namespace tdf
