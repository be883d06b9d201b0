#pragma once
/// nvdiffrast's `dr.antialias` forward pass on the CPU (analytic silhouette antialiasing, Laine
/// et al. 2020, "Modular Primitives for High-Performance Differentiable Rendering", sec. 3.3;
/// spec 3.6).
///
/// For every pair of horizontally or vertically adjacent pixels with different triangle ids the
/// front triangle (smaller depth; the only one when the other pixel is background) is tested for
/// a silhouette edge (an edge whose neighbouring triangle across it lies on the same side in
/// screen space, or that has no neighbour) crossing the segment between the two pixel centres,
/// within 1/16 pixel, and more vertical than horizontal for a horizontal pair (the reverse for a
/// vertical pair). With the crossing at fraction d from the front triangle's pixel toward the
/// other, alpha = 0.5 - d: when positive, the front pixel takes alpha of the other's colour;
/// when negative, the other pixel takes -alpha of the front pixel's colour. A straight edge thus
/// gives each pixel its exact area coverage. Contributions read the input image and are summed
/// in a fixed order, so the result is bit-identical on any thread count (the GPU adds them
/// atomically in any order).
///
/// The G-buffer of either visibility producer works: it has the triangle ids and a depth that
/// orders surfaces as z/w does.
#include <tdf/core/image.h>
#include <tdf/core/vec.h>

#include <cstdint>
#include <vector>

namespace tdf {

/// The mesh topology dr.antialias uses: for every triangle edge, the vertex opposite to it in
/// the neighbouring triangle (by position index; the first other triangle found in index order
/// for non-manifold edges), or -1 on a boundary.
class EdgeTopology {
public:
    EdgeTopology() = default;
    EdgeTopology(const std::vector<Vec3i>& triangles, std::size_t vertex_count);
    /// Opposite vertices across the edges (v1 v2), (v2 v0), (v0 v1) of triangle t.
    const Vec3i& opposite(int t) const { return m_opposite[std::size_t(t)]; }
    std::size_t triangle_count() const { return m_opposite.size(); }

private:
    std::vector<Vec3i> m_opposite;
};

/// The pixel pairs dr.antialias blends for one view, found once and applied to any number of
/// images of that view.
class AntialiasPlan {
public:
    /// `triangle` (-1 = background) and `depth` per pixel (row-major, width x height); `clip`
    /// are the clip-space positions the view was rasterized with (raster.h clip_positions()).
    void analyze(int width, int height, const int* triangle, const float* depth,
                 const std::vector<Vec4f>& clip, const std::vector<Vec3i>& triangles,
                 const EdgeTopology& topology);
    /// Blends `image` (width x height, any channel count) in place.
    void apply(Image& image) const;
    /// Pixel pairs with a silhouette crossing (for tests and statistics).
    std::size_t blended_pairs() const;

private:
    int m_width = 0, m_height = 0;
    // alpha of the pair (pixel, right neighbour) and (pixel, pixel below); 0 = no blend.
    std::vector<float> m_alpha_right, m_alpha_down;
    std::vector<std::uint8_t> m_touched_rows;  // rows with any non-zero alpha (skipped otherwise)
};

}  // namespace tdf
