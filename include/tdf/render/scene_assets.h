#pragma once
/// Everything `tdf render` needs for a scene file: the loaded (and optionally normalised) mesh,
/// its Embree scene, textures, material, render settings, passes, views and lights.
#include <tdf/core/image.h>
#include <tdf/render/renderer.h>
#include <tdf/scene/scene_file.h>
#include <tdf/scene/scene_views.h>

#include <memory>
#include <vector>

namespace tdf {

/// What load_scene_assets did to the file's coordinates ("normalize": true):
/// scene = (file - center) * scale. Identity otherwise.
struct MeshNormalization {
    Vec3f center{0, 0, 0};
    float scale = 1.0f;
};

struct SceneAssets {
    SceneDescription description;
    TriangleMesh mesh;
    std::unique_ptr<EmbreeScene> scene;
    MipTexture albedo;   ///< empty unless the albedo source is a texture
    MipTexture tactile;  ///< the first tactile image, decoded (empty without one)
    MipTexture label;
    SurfaceMaterial material;  ///< points into this object: SceneAssets is not copyable
    RenderSettings settings;
    std::vector<Pass> passes;
    std::vector<SceneView> views;
    MeshNormalization normalization;

    /// `mesh` in the input file's own coordinates (normalisation undone; UVs, tangents, normals
    /// and face groups as rendered), without the albedo image: what exports write.
    TriangleMesh export_mesh() const;

    SceneAssets() = default;
    SceneAssets(const SceneAssets&) = delete;
    SceneAssets& operator=(const SceneAssets&) = delete;
};

/// Loads the mesh and images a scene names. When the scene has tactile images and the mesh has
/// UVs, they are measured (measure_atlas) and overlaps, unmapped faces and mirrored charts are
/// warned about with their counts; `"uv": {"reunwrap": true}` (or a mesh without UVs) builds a
/// new atlas with `tdf atlas`'s defaults and re-bakes the mesh's albedo texture onto it. Albedo
/// source "mesh" uses the mesh's texture, else its vertex colours, else constant grey 0.5 with
/// a warning (the reference's fallback, spec 1.2). Throws tdf::Error naming the scene and the
/// file on missing or bad input.
std::unique_ptr<SceneAssets> load_scene_assets(const SceneDescription& description);


/// The tactile layout a scene asks for (its "tactile_layout" section: mode atlas, or physical with
/// mm_per_unit and mm_per_pixel, the latter defaulting to the map's own metadata), for a map of
/// `map_width` pixels. One transform for `tdf render` and `tdf optimize`. Throws tdf::Error naming
/// the scene when the physical size cannot be known.
TactileLayoutTransform resolve_tactile_layout(const SceneDescription& description, const TriangleMesh& mesh,
                                              int map_width, float map_mm_per_pixel);

/// The light of view `index` (LightSpec modes). magic3d draws from
/// Rng::stream(seed, 0x4c49474854 + index) so lights and views have separate streams.
Light scene_light(const SceneDescription& description, const SceneView& view, std::size_t index);

}  // namespace tdf
