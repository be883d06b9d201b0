#include <tdf/scene/view_sampler.h>

#include <tdf/core/error.h>

#include <algorithm>
#include <cmath>

namespace tdf {

int ssaa_internal_resolution(int resolution, float ssaa) {
    if (ssaa == 1.f) return resolution;
    return int(std::ceil(float(resolution) * ssaa / 8.f)) * 8;
}

VisualView sample_visual_view(Rng& rng, const VisualViewOptions& options) {
    TDF_CHECK(options.min_elevation < options.max_elevation);
    TDF_CHECK(options.min_azimuth < options.max_azimuth);
    VisualView view;
    view.elevation_deg = float(rng.uniform_int(options.min_elevation, options.max_elevation));
    view.azimuth_deg = float(rng.uniform_int(options.min_azimuth, options.max_azimuth));
    view.radius = options.radius + rng.uniform(options.radius_range_min, options.radius_range_max);
    view.ssaa = options.random_ssaa ? std::min(2.f, std::max(1.f, 2.f * rng.uniform())) : 1.f;
    view.output_resolution = options.resolution;
    view.internal_width = view.internal_height = ssaa_internal_resolution(options.resolution, view.ssaa);
    view.camera = Camera::orbit(view.elevation_deg, view.azimuth_deg, view.radius, options.fovy_degrees,
                                view.internal_width, view.internal_height, options.target);
    return view;
}

Camera sample_patch_view(Rng& rng, const TriangleMesh& mesh, int resolution, float distance, float half_extent,
                         bool reference_flip) {
    TDF_CHECK(!mesh.positions.empty() && mesh.normals.size() == mesh.positions.size());
    const int vertex = rng.uniform_int(0, int(mesh.positions.size()));
    Camera camera = Camera::tactile_patch(mesh.positions[std::size_t(vertex)], mesh.normals[std::size_t(vertex)],
                                          resolution, resolution, distance, half_extent);
    camera.flip_rows = reference_flip;
    return camera;
}

}  // namespace tdf
