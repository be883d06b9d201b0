#pragma once
/// Packing flattened charts into one square texture.
#include <tdf/core/vec.h>

#include <vector>

namespace tdf {

/// One chart to pack: its flattened triangles in any position and orientation. The packer only
/// rotates, uniformly scales and translates them, so orientation (no mirroring) and relative
/// texel density are kept.
struct PackChart {
    std::vector<Vec2f> uvs;
    std::vector<Vec3i> triangles;  ///< indices into `uvs`; zero-area triangles are allowed
};

/// Packs `charts` into the unit square, rewriting their `uvs` in place, for a `size` x `size`
/// texture with at least `gutter` empty texels between any two charts' texels (and gutter/2 to
/// the border). Charts are packed by shape, not by bounding box: each is turned to its
/// minimal-area bounding rectangle, rasterized conservatively (every texel a triangle touches),
/// dilated by ceil(gutter/2), and placed, largest first, at the lowest (then leftmost) free
/// position of a texel bitmap over four quarter turns, so small charts fill holes left between
/// big ones. Free-run tables make the search skip occupied stretches. The scale (texels per
/// input unit) is the largest found, by shrinking then bisecting to 0.3 %, at which one of three
/// largest-first orders (bounding-rectangle area, longest side, area) fits every chart; it is
/// returned. Deterministic. Throws tdf::Error when the charts do not fit even at 1/1000 of the
/// area-filling scale.
double pack_charts(std::vector<PackChart>& charts, int size, int gutter);

}  // namespace tdf
