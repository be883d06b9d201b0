#pragma once
/// Bilinear image resizing with PyTorch `interpolate(mode="bilinear", align_corners=False)`
/// semantics and no antialias prefilter (spec 3.8): destination texel d samples the source at
/// (d + 0.5) * src/dst - 0.5, clamped below at 0, neighbours clamped at the last texel. Used
/// to bring SSAA renders back to the output size (every channel, the mask included) and, with
/// the adjoint, to carry image gradients back to the internal resolution.
#include <tdf/core/image.h>

namespace tdf {

/// Resizes `src` to width x height (any sizes: down- or up-sampling), all channels.
Image downsample_bilinear(const Image& src, int width, int height);

/// The exact adjoint (transpose) of downsample_bilinear for a src_width x src_height source:
/// <downsample_bilinear(x), y> == <x, downsample_bilinear_adjoint(y)> for all x, y. `grad_out`
/// has the destination size; the result has the source size.
Image downsample_bilinear_adjoint(const Image& grad_out, int src_width, int src_height);

}  // namespace tdf
