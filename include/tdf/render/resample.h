#pragma once
/// The renderer's SSAA resize under its historical names (spec 3.8); the operations live in
/// core/image_ops.h (resize_bilinear, resize_bilinear_adjoint).
#include <tdf/core/image_ops.h>

namespace tdf {

/// resize_bilinear(): PyTorch interpolate(mode="bilinear", align_corners=False), no antialias.
inline Image downsample_bilinear(const Image& src, int width, int height) {
    return resize_bilinear(src, width, height);
}

/// resize_bilinear_adjoint(): the exact transpose of downsample_bilinear.
inline Image downsample_bilinear_adjoint(const Image& grad_out, int src_width, int src_height) {
    return resize_bilinear_adjoint(grad_out, src_width, src_height);
}

}  // namespace tdf
