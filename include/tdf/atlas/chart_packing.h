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
/// dilated by ceil(gutter/2), and dropped onto a skyline at the column and 90-degree turn that
/// keep the skyline lowest (then waste least); a binary search on the scale finds the largest
/// one at which all charts fit. Returns that scale (texels per input unit).
/// Deterministic. Throws tdf::Error when not even a 1-texel-per-chart layout fits.
double pack_charts(std::vector<PackChart>& charts, int size, int gutter);

}  // namespace tdf
