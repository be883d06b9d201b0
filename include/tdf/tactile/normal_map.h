#pragma once
/// Height maps to tangent-space normal maps and back (spec 6.4), in the OpenGL convention:
/// x = red = right, y = green = up (towards row 0), z = blue = out of the surface.
#include <tdf/core/image.h>

#include <string>

namespace tdf {

/// Matches reference: the amplitude factor k of spec 6.4 step 3 for a patch whose height range
/// is `scale_mm` (k = 1.25 above 20, 1.5 above 10, 3 above 5, else 5).
float reference_amplitude_factor(float scale_mm);

/// Unit normals (3 channels, decoded, [-1, 1]) of the surface z = gain * height, where `height`
/// is 1 channel and `gain` converts its units to pixel widths (1 / mm_per_pixel for heights
/// in mm at physical scale). Matches reference (spec 6.4 step 4): central differences on the
/// interior, border gradients copied from the nearest interior pixel, n = normalize(-dz/dx,
/// -dz/dy_up, 1). With `wrap` (a tileable map) the differences are periodic instead, so the
/// first and last rows and columns are not copies of their neighbours and the map tiles
/// without a seam. Needs at least 3 x 3 pixels.
Image normals_from_height(const Image& height, float gain, bool wrap = false);

/// Heights (1 channel, zero mean, in pixel widths) whose normals are `normals` (3+ channels,
/// decoded): the gradients -nx/nz and +ny/nz (row direction) integrated with the Poisson
/// solver. nz is clamped to at least `min_nz` so grazing normals cannot blow up.
Image height_from_normals(const Image& normals, float min_nz = 0.1f, const std::string& what = "normal map");

/// Normals whose slopes (nx / nz, ny / nz) are `factor` times those of `normals` (3+
/// channels; unit length out): the same surface with its relief scaled, like `--strength`.
Image scale_normal_slopes(const Image& normals, float factor);

/// Encodes decoded normals for an image file: (n + 1) / 2 in [0, 1]. Written by write_png with
/// Quantize::Truncate this is the reference's floor((n * 0.5 + 0.5) * 255) (spec 6.4 step 5).
Image encode_normals(const Image& normals);

}  // namespace tdf
