#pragma once
/// Per-pixel surface data of one view, structure of arrays (one vector per attribute,
/// index = y * width + x, row 0 = top). Background pixels have mask 0, triangle -1 and every
/// other attribute zero (as the rasterizer's interpolation gives, spec 3.1).
///
/// The one interface between visibility and shading: the ray tracer (trace.h) and the
/// rasterizer (raster.h) both produce it, and the renderer shades it with one code path (a tile
/// at a time in structure-of-arrays form, gbuffer_lanes.h, which the tracer fills directly).
#include <tdf/core/default_init_allocator.h>
#include <tdf/core/vec.h>

#include <cstddef>
#include <vector>

namespace tdf {

/// One attribute of a G-buffer. Large arrays start on a cache line (default_init_allocator.h):
/// the tracer writes them a line at a time with streaming stores (stream_lanes.h), and a row that
/// starts mid-line leaves half-written lines at every tile's edge.
template <typename T>
using PixelArray = std::vector<T, DefaultInitAllocator<T>>;

/// Which attributes a G-buffer holds. `Shading` leaves out the hit's triangle, barycentrics and
/// depth (those vectors stay empty): what an optimizer that only looks the maps up and shades
/// reads, 16 of the 84 bytes a pixel not written.
enum class GBufferFields { All, Shading };

struct GBuffer {
    int width = 0;
    int height = 0;
    GBufferFields fields = GBufferFields::All;
    PixelArray<float> mask;         ///< 1 hit, 0 background
    PixelArray<int> triangle;       ///< index into TriangleMesh::triangles, -1 background
    PixelArray<Vec2f> barycentric;  ///< (b1, b2): p = (1-b1-b2) p0 + b1 p1 + b2 p2
    PixelArray<Vec3f> position;     ///< world-space hit point
    PixelArray<float> depth;        ///< -z_cam (distance along -back from the camera plane)
    PixelArray<Vec3f> normal;       ///< normalize(interpolated vertex normals) N
    PixelArray<Vec3f> tangent;      ///< normalize(interpolated corner tangents) T
    PixelArray<float> handedness;   ///< w of the tangent frame, +1 or -1
    PixelArray<Vec2f> uv;           ///< interpolated UV, OBJ convention (v up); 0 without UVs
    PixelArray<Vec2f> duv_dx;  ///< d uv / d pixel x (ray differentials, or dr.interpolate's analytic ones)
    PixelArray<Vec2f> duv_dy;  ///< d uv / d pixel y (pixel y grows down the image)

    /// Sizes every attribute `new_fields` holds for width x height pixels (contents unspecified)
    /// and empties the others.
    void resize(int new_width, int new_height, GBufferFields new_fields = GBufferFields::All);
    bool has_ids_and_depth() const { return fields == GBufferFields::All; }
    std::size_t pixel_count() const { return std::size_t(width) * std::size_t(height); }
    std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
    /// Sets pixel i to background.
    void clear_pixel(std::size_t i);
};

}  // namespace tdf
