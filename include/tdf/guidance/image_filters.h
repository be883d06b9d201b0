#pragma once
/// Small image filters shared by the built-in guidance backends. All are parallel over rows and
/// write disjoint outputs, so results do not depend on the thread count.
#include <tdf/core/image.h>

namespace tdf {

/// Mask-weighted separable Gaussian blur: out = G*(m x) / G*(m) per channel, so background
/// (mask 0) does not bleed into the foreground. `mask` is 1 channel of the image's size, or empty
/// for weight 1 everywhere. Pixels whose blurred weight is 0 keep their value. `sigma` in pixels;
/// the kernel has radius ceil(3 sigma) and clamps at the borders. sigma <= 0 returns a copy.
Image gaussian_blur_masked(const Image& image, const Image& mask, float sigma);

/// resize_bilinear(gaussian_blur_masked(image, mask, sigma), width, height), the same numbers,
/// but the blur is evaluated only at the pixels the bilinear lookup reads (horizontal taps at
/// the needed columns of the needed rows, vertical taps at the needed pixels). Shrinking a
/// 512^2 image 19x this costs about a twentieth of blurring it whole, which is what a
/// prefiltered coarse copy needs: anti-aliased downsampling without full-size temporaries.
Image gaussian_blur_resized(const Image& image, const Image& mask, float sigma, int width, int height);

/// Halves the size (rounding up) by averaging 2x2 blocks (edge blocks average what exists).
Image downsample_half(const Image& image);

/// Resamples to width x height with bilinear interpolation (pixel centres at i + 0.5, clamped
/// at the borders).
Image resize_bilinear(const Image& image, int width, int height);

}  // namespace tdf
