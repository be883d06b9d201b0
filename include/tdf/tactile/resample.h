#pragma once
/// Cropping float images (any channel count). Lanczos resampling (resize_lanczos) is a core
/// image operation: see core/image_ops.h.
#include <tdf/core/image.h>
#include <tdf/core/image_ops.h>

namespace tdf {

/// Columns [x, x + width) and rows [y, y + height); the box must lie inside the image.
Image crop(const Image& image, int x, int y, int width, int height);

}  // namespace tdf
