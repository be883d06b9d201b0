#pragma once
/// Visibility by rasterization with nvdiffrast's rules (spec 2.2, 3.1 steps 1-3): the CPU
/// counterpart of `dr.rasterize` and `dr.interpolate`, producing the same GBuffer as the ray
/// tracer (trace.h) so both feed one shading pipeline.
///
/// Rules reproduced:
/// - clip-space positions from the camera's own matrices: v_cam = view * [p, 1], then
///   v_clip = projection * v_cam, each in float32 (Camera::view_matrix/projection_matrix);
/// - pixel (i, j) centred at (j + 0.5, i + 0.5), row i = NDC y (2i+1)/H - 1 (row 0 = NDC -1);
/// - coverage by homogeneous (2-D projective) edge functions evaluated in double at the pixel
///   centre, so triangles crossing w = 0 need no clipping; a centre exactly on an edge belongs
///   to the triangle for which that edge is a top or left edge (top = interior at larger rows),
///   which keeps shared edges watertight: every centre is covered exactly once by a closed mesh;
/// - clipping: only -w <= z_clip <= w (the planar near and far planes; x and y are the screen);
/// - no culling; depth test on z/w, strictly less, triangles in index order (ties: lowest index);
/// - output per pixel as dr.rasterize: (u, v, z/w, triangle_id + 1) in float32 with
///   perspective-correct barycentrics, p = u p0 + v p1 + (1 - u - v) p2, and all zeros on the
///   background; rast_db = (du/dx, du/dy, dv/dx, dv/dy) per pixel, analytic (not differenced).
///
/// Not bit-identical to a GPU: a GPU snaps vertices to a sub-pixel grid before the coverage test,
/// so centres very close to an edge may go the other way, and it computes barycentrics in its own
/// float order (against Mesa's llvmpipe: the same triangle on 99.92 % of the pixels, barycentric
/// differences of median 3e-6; docs/commands/render.md).
///
/// Parallel: triangles are set up in fixed chunks, binned to 64x64-pixel tiles in chunk order,
/// and each tile rasterized by one thread in triangle order, so the result is bit-identical on
/// any thread count.
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/gbuffer.h>
#include <tdf/scene/camera.h>

#include <vector>

namespace tdf {

/// Side of the square tiles triangles are binned to.
constexpr int kRasterTile = 64;

/// What dr.rasterize returns for one image (structure of arrays, index = y * width + x).
struct RasterBuffer {
    int width = 0;
    int height = 0;
    std::vector<Vec4f> rast;     ///< (u, v, z/w, triangle_id + 1); (0, 0, 0, 0) on the background
    std::vector<Vec4f> rast_db;  ///< (du/dx, du/dy, dv/dx, dv/dy) per pixel (x right, y down rows)

    std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
    /// Triangle index at pixel i, or -1.
    int triangle(std::size_t i) const { return int(rast[i].w) - 1; }
};

/// Clip-space positions of the mesh's vertices for `camera` (float32, as the reference computes
/// them: v_cam = view [p, 1], v_clip = projection v_cam).
std::vector<Vec4f> clip_positions(const TriangleMesh& mesh, const Camera& camera);

/// Rasterizes `triangles` (indices into `clip`) into a width x height RasterBuffer, reusing
/// `out`'s allocations. Invalid indices are an error.
void rasterize(const std::vector<Vec4f>& clip, const std::vector<Vec3i>& triangles, int width, int height,
               RasterBuffer& out);

/// dr.interpolate of the mesh's attributes into G-buffer pixels [x0, x1) x [y0, y1) of `tile`
/// (resized to (x1 - x0) x (y1 - y0) when needed; tile pixel (0, 0) is image pixel (x0, y0)):
/// world position, -z_cam, normalize(interpolated normal), normalize(interpolated tangent) and
/// its sign, UV and its screen-space derivatives duv/dx = du/dx (uv0 - uv2) + dv/dx (uv1 - uv2)
/// (the same for y) from rast_db. Barycentrics are stored in GBuffer's convention:
/// (b1, b2) = (v, 1 - u - v). Background pixels are cleared (GBuffer::clear_pixel).
void interpolate_tile(const RasterBuffer& raster, const TriangleMesh& mesh, const Camera& camera, int x0,
                      int y0, int x1, int y1, GBuffer& tile);

/// rasterize() + interpolate_tile() over the whole image: the raster counterpart of
/// trace_gbuffer(). Deterministic for any thread count.
void raster_gbuffer(const TriangleMesh& mesh, const Camera& camera, GBuffer& out);

}  // namespace tdf
