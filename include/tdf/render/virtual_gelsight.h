#pragma once
/// A virtual GelSight (issue 24): presses a sensor pad onto an exported asset (mesh + the height
/// map written beside its normal map) and says what the sensor would measure, so that a run can
/// check that touching the finished asset feels like the captured surface.
///
/// The pad is the near-surface tactile camera (Camera::tactile_patch): orthographic, square
/// pixels of the capture's pitch, looking along -n of the touched point. Embree rays find the
/// mesh under every pixel; the relief is the asset's height map at the hit's UV, displaced along
/// the hit's normal. The gel is taken to conform to the whole pad (a full press): every pixel
/// measures the surface's height above the lowest point under the pad, in mm.
#include <tdf/core/image.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/texture.h>
#include <tdf/scene/embree_scene.h>
#include <tdf/tactile/height_map.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tdf {

/// The sensor: width x height pixels of mm_per_pixel (GelSight Mini's pitch by default).
struct GelSightPad {
    int width = 240, height = 240;
    float mm_per_pixel = kGelSightMiniMmPerPixel;
};

/// An exported asset that carries its relief: `<stem>.obj`, its `<stem>.mtl` with a `disp -mm
/// base gain <stem>_height.png` line, and `<stem>_height.exr` in mm.
struct ReliefAsset {
    std::string obj_path;
    TriangleMesh mesh;
    std::unique_ptr<EmbreeScene> scene;
    HeightMap height;       ///< mm; height.mm_per_pixel = mm per texel
    MipTexture height_texture;  ///< the same, for bilinear lookups at hit UVs
    float mm_per_unit = 0;  ///< from the MTL's disp gain and the EXR's range
};

/// Loads the asset in `folder`: the one `<stem>.obj` whose `<stem>_height.exr` exists (a run's
/// `_initialized` export is skipped when the final one is there). Throws tdf::Error naming the
/// folder when it holds no such asset, or the file that is wrong.
std::unique_ptr<ReliefAsset> load_relief_asset(const std::string& folder);

/// Where a pad is pressed: a surface point and its (interpolated, unit) normal.
struct TouchPoint {
    Vec2f uv;  ///< OBJ convention, v up
    Vec3f position, normal;
    int triangle = -1;
};

/// The point of `mesh` at texture coordinate `uv` (the first face whose UV triangle holds it);
/// nothing when no face does.
std::optional<TouchPoint> touch_point_at_uv(const TriangleMesh& mesh, Vec2f uv);

/// `count` points drawn uniformly over the surface area (face by area, then a uniform point in
/// it) from Rng(seed). The same seed gives the same points.
std::vector<TouchPoint> random_touch_points(const TriangleMesh& mesh, int count, std::uint64_t seed);

/// What the sensor measures at one touch.
struct SimulatedTouch {
    HeightMap height;  ///< pad-sized, mm above the lowest point, mm_per_pixel = the pad's pitch
    Image normals;     ///< decoded tangent-space normals of `height` (normals_from_height)
    Image preview;     ///< RGB: the normals lit by three coloured lights, like a GelSight image
    std::vector<int> triangles;  ///< per pad pixel (row-major), the mesh face under it
};

/// Presses `pad` at `point`. Throws tdf::Error when a pixel of the pad misses the mesh (the
/// pad is larger than the part it lands on), naming the pad's size in mm.
SimulatedTouch simulate_touch(const ReliefAsset& asset, const TouchPoint& point, const GelSightPad& pad);

/// Normals lit like a GelSight image: three coloured lights 120 degrees apart, 45 degrees up;
/// RGB in [0, 1].
Image gelsight_preview(const Image& normals);

}  // namespace tdf
