#pragma once
/// The guidance backends' image filters (gaussian_blur_masked, gaussian_blur_resized,
/// downsample_half, resize_bilinear) are core image operations: see core/image_ops.h.
#include <tdf/core/image_ops.h>
