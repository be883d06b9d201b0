#include <tdf/scene/scene_views.h>

#include <tdf/scene/view_sampler.h>

#include <fmt/format.h>

namespace tdf {

std::vector<SceneView> make_scene_views(const SceneDescription& scene, const TriangleMesh& mesh) {
    const ViewsSpec& spec = scene.views;
    std::vector<SceneView> views;
    auto add_orbit = [&](float elevation, float azimuth, float radius, float fovy, const std::string& kind) {
        SceneView v;
        v.label = fmt::format("{} elevation {} azimuth {} radius {}", kind, elevation, azimuth, radius);
        v.camera = Camera::orbit(elevation, azimuth, radius, fovy, scene.width, scene.height, spec.target);
        v.ssaa = scene.ssaa;
        v.has_angles = true;
        v.elevation = elevation;
        v.azimuth = azimuth;
        views.push_back(v);
    };
    for (const auto& o : spec.orbit) add_orbit(o.elevation, o.azimuth, o.radius, o.fovy, "orbit");
    for (int k = 0; k < spec.turntable_count; ++k)
        add_orbit(spec.turntable_elevation, 360.f * float(k) / float(spec.turntable_count), spec.radius, spec.fovy,
                  "turntable");
    for (int k = 0; k < spec.random_count; ++k) {
        Rng rng = Rng::stream(scene.seed, 2 * std::uint64_t(k));
        VisualViewOptions options;
        options.resolution = scene.width;
        options.random_ssaa = spec.random_ssaa;
        options.fovy_degrees = spec.fovy;
        options.target = spec.target;
        const VisualView sampled = sample_visual_view(rng, options);
        add_orbit(sampled.elevation_deg, sampled.azimuth_deg, sampled.radius, spec.fovy, "random");
        views.back().camera.height = scene.width;  // visual views are square (spec 2.3)
        views.back().ssaa = sampled.ssaa;
    }
    for (int k = 0; k < spec.patch_count; ++k) {
        Rng rng = Rng::stream(scene.seed, 2 * std::uint64_t(k) + 1);
        SceneView v;
        v.camera = sample_patch_view(rng, mesh, scene.width, 0.1f, 0.075f, spec.patch_reference_flip);
        v.label = fmt::format("patch at ({:.3f}, {:.3f}, {:.3f})", v.camera.position.x, v.camera.position.y,
                              v.camera.position.z);
        views.push_back(v);
    }
    return views;
}

}  // namespace tdf
