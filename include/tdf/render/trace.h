#pragma once
/// Primary-ray tracing into a GBuffer: Embree packets (16-wide on AVX-512 CPUs, otherwise
/// 8-wide), 64x4 tiles in parallel. Clipping is the rasterizer's planar near/far (spec 2.2),
/// there is no back-face culling, and pixel centres are at (j + 0.5, i + 0.5).
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/gbuffer.h>
#include <tdf/render/gbuffer_lanes.h>
#include <tdf/scene/camera.h>
#include <tdf/scene/embree_scene.h>

#include <vector>

namespace tdf {

/// The tiles traced (and shaded) in parallel: kTraceTileWidth x kTraceTileHeight pixels, one
/// 16-wide packet tall. Wide and short, so that a tile touches few rows: a tile row is four cache
/// lines of each float array of a full-frame G-buffer, and a tile spans 2 pages of it where a
/// 16x16 tile spanned 8 (the main job's tracing: 0.060 -> 0.040 s per refinement iteration,
/// docs/measurements.md).
constexpr int kTraceTileWidth = 64;
constexpr int kTraceTileHeight = 4;
constexpr int kTraceTilePixels = kTraceTileWidth * kTraceTileHeight;

/// Traces camera.width x camera.height primary rays. `mesh` must be the mesh `scene` was built
/// from (its attributes are interpolated at the hits). Deterministic for any thread count.
GBuffer trace_gbuffer(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera);
/// The same, reusing `out`'s allocations; `fields` chooses what it holds (GBufferFields).
void trace_gbuffer(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera, GBuffer& out,
                   GBufferFields fields = GBufferFields::All);
/// Traces the pixels [x0, x1) x [y0, y1) of the camera's image into lanes (gbuffer_lanes.h), a
/// packet at a time in packet order (lane pixel (0, 0) is image pixel (x0, y0)): the values
/// trace_gbuffer gives those pixels, for a renderer that shades each tile right after tracing it,
/// from a small, cache-resident buffer. The tile holds at most GBufferLanes::kMax pixels.
void trace_tile_lanes(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera, int x0,
                      int y0, int x1, int y1, GBufferLanes& out);
static_assert(kTraceTilePixels == GBufferLanes::kMax, "a trace tile fills the lanes");

/// Baseline for benchmarks: the same packets and tiles, closest hit only; writes the hit
/// distance (0 on a miss) per pixel to `t` and returns the number of hits.
std::size_t trace_closest_hits(const EmbreeScene& scene, const Camera& camera, std::vector<float>& t);

/// One ray with rtcIntersect1, for tests and picking: the hit's triangle (or -1), its
/// barycentrics and distance.
struct RayHit {
    int triangle = -1;
    Vec2f barycentric;
    float t = 0;
};
RayHit trace_ray(const EmbreeScene& scene, const Ray& ray);

}  // namespace tdf
