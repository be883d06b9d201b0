#pragma once
/// Ambient occlusion from a height map (issue 24's derived map for texture artists): how much of
/// the sky above each texel its own relief hides, the map a PBR material multiplies its ambient
/// light by (glTF's occlusionTexture). Horizon-based: along kAoDirections directions the highest
/// elevation angle of the relief within kAoRadiusTexels texels is found, and the texel's
/// occlusion is the mean sine of those horizons. Tileable when the height map is.
#include <tdf/core/image.h>

#include <vector>

namespace tdf {

constexpr int kAoDirections = 8;
constexpr int kAoRadiusTexels = 16;

/// The ambient occlusion of `height` (1 channel; heights in the same unit as `texel_size`, the
/// lateral size of a texel, e.g. both mm) as visibility in [0, 1] (1 = open sky, 0 = fully hidden),
/// 1 channel. `periodic`: lookups wrap (a tileable map), else a march stops at the border.
/// `region` (per texel, row-major; empty = one region): a march stops where the region changes
/// or is negative, so an atlas's charts do not shade each other through the gutter. Parallel
/// per row; the same result on any thread count.
Image ambient_occlusion(const Image& height, float texel_size, bool periodic, const std::vector<int>& region = {});

}  // namespace tdf
