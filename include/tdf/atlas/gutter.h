#pragma once
/// Gutter dilation ("UV padding"): fills texels outside the UV charts from the covered texels
/// next to them, so bilinear and mip-mapped lookups near a seam never blend in background.
///
/// Replaces the reference's OpenCV Telea inpainting (spec 1.5), which takes ~2 min at 1024^2:
/// here each pass gives every empty texel that touches the filled region (8-neighbourhood) the
/// mean of its filled neighbours, edge neighbours weighted 2 and diagonal ones 1; the newly
/// filled texels join the region for the next pass. Passes read only the previous pass's
/// values (double-buffered), so the result does not depend on the visiting order or on threads.
/// Cost O(texels filled): 87 ms of CPU to fill 700k empty texels of a 1024^2 RGB map. Values
/// stay in float (no 8-bit round trip).
#include <tdf/core/image.h>

#include <vector>

namespace tdf {

/// Fills empty texels of `image` from covered ones, `texels` rings deep (Chebyshev distance);
/// `texels` <= 0 fills every empty texel reachable from a covered one (use this before mip
/// mapping). `coverage` has one entry per pixel (row-major, like UvRaster::triangle): >= 0 =
/// covered (a triangle id or 1), < 0 = empty. Works for any channel count. When nothing is
/// covered the image is left as it is.
/// Throws tdf::Error when `coverage.size()` differs from the pixel count.
void dilate_gutter(Image& image, const std::vector<int>& coverage, int texels);

}  // namespace tdf
