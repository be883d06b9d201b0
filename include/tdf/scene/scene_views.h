#pragma once
/// The cameras a scene file asks for, in order: explicit orbit views, the turntable, seeded
/// random visual views (spec 2.3) and seeded tactile patch views (spec 2.4).
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/scene/camera.h>
#include <tdf/scene/scene_file.h>

#include <string>
#include <vector>

namespace tdf {

struct SceneView {
    std::string label;    ///< e.g. "orbit e=0 a=90", for logs
    Camera camera;        ///< at the OUTPUT resolution
    float ssaa = 1.f;     ///< render at ssaa_internal_resolution() and resize back
    bool has_angles = false;  ///< orbit views: elevation/azimuth below are meaningful
    float elevation = 0;
    float azimuth = 0;
};

/// Builds every view of `scene`. Random draws come from Rng::stream(seed, k): stream 2k for
/// the k-th random visual view, 2k+1 for the k-th patch view, so adding views of one kind does
/// not change the others. `mesh` (normalised as the scene says) anchors the patch views.
std::vector<SceneView> make_scene_views(const SceneDescription& scene, const TriangleMesh& mesh);

}  // namespace tdf
