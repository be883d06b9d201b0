#pragma once
/// How the texels of a UV atlas lie on the surface (issue 24): the length and direction of one
/// texel step in the surface's tangent frame, and which texels meet across a UV seam. A
/// tangent-space normal map holds slopes per unit of surface length, whatever a texel's size on
/// the surface; the heights those slopes stand for are only right when they are integrated over
/// the surface's own lengths, and level across the seams where the atlas cuts the surface open.
#include <tdf/atlas/uv_raster.h>
#include <tdf/mesh/triangle_mesh.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace tdf {

/// One texel step in mesh units, in the texel's face's tangent frame (T along +u, B the +v side
/// of the tangent plane, perpendicular to T, as the renderer's frame): a step to the next column
/// (+x, +u) goes `along_x_t` along T; a step to the next row (+y, -v) goes `along_y_t` along T
/// and `along_y_b` along B. An isometric UV map at s mesh units per UV unit gives
/// (s / size, 0, -s / size).
struct TexelStep {
    float along_x_t = 0, along_y_t = 0, along_y_b = 0;
};

struct SurfaceTexels {
    int size = 0;
    std::vector<std::uint32_t> texels;  ///< row-major indices of the covered texels, ascending
    std::vector<int> node;              ///< per texel of the map: its index in `texels`, or -1
    std::vector<int> chart;             ///< per covered texel: its face's UV chart (uv_charts)
    std::vector<TexelStep> step;        ///< per covered texel
    /// Pairs of covered texels (indices into `texels`, first < second) on the two sides of a UV
    /// seam edge, about one texel apart on the surface: sorted, no duplicates.
    std::vector<std::pair<int, int>> seam_links;

    std::size_t covered_count() const { return texels.size(); }
};

/// Builds the table for `mesh` (with UVs) over `raster` (rasterize_uv, partial texels included
/// or not). Texels of faces whose UV triangle has no area get the step of an isometry at the
/// mesh's mean scale. Seam edges whose UV length is zero on either side are skipped.
SurfaceTexels surface_texels(const TriangleMesh& mesh, const UvRaster& raster);

}  // namespace tdf
