#pragma once
/// Cropping and Lanczos resampling of float images (any channel count).
#include <tdf/core/image.h>

namespace tdf {

/// Columns [x, x + width) and rows [y, y + height); the box must lie inside the image.
Image crop(const Image& image, int x, int y, int width, int height);

/// Lanczos-4 resampling (8 taps, OpenCV INTER_LANCZOS4 when enlarging: source position
/// (i + 0.5) * scale - 0.5, borders replicated, weights normalised to sum 1). When shrinking, the
/// kernel is widened by the shrink factor so that it also low-passes (OpenCV does not). Values
/// are not clamped: like the reference, results can overshoot the input range slightly.
Image resize_lanczos(const Image& image, int width, int height);

}  // namespace tdf
