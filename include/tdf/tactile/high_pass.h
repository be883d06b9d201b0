#pragma once
/// High-pass filters that keep a capture's texture and drop its overall shape (spec 6.2 step 2),
/// plus the edge-preserving smoothing the reference applies afterwards (step 3).
#include <tdf/core/image.h>

namespace tdf {

/// Matches reference: zeroes a square block of the centred 2-D spectrum, rows
/// [H/2 - t, H/2 + t) x cols [W/2 - t, W/2 + t) (DC included), keeps the real part of the
/// inverse transform and subtracts its minimum (spec 6.2 step 2). Because the block is
/// one bin longer on the negative side, the real part passes the frequencies -t (per axis)
/// at half amplitude. `threshold` t >= 1 in frequency bins; the image (1 channel) must be larger
/// than 2t in both directions. The result has minimum 0, same units as the input.
Image high_pass_fft_block(const Image& height, int threshold = 5);

/// Gaussian high-pass h - G * h with a cut-off wavelength in millimetres (ISO 16610-61 Gaussian:
/// half the amplitude of a sine of wavelength `cutoff_mm` passes; sigma = 0.1874 cutoff),
/// mirrored borders, shifted to minimum 0 like the reference filter. Unlike the FFT block
/// filter its cut-off is physical, so captures at different resolutions filter alike.
Image high_pass_gaussian(const Image& height, float cutoff_mm, float mm_per_pixel);

/// Bilateral filter with OpenCV's semantics for float images (`cv::bilateralFilter`): a disc of
/// radius diameter/2 pixels, spatial weight exp(-r^2 / (2 sigma_space^2)), range weight
/// exp(-dv^2 / (2 sigma_color^2)) in the image's units, mirrored (reflect-101) borders.
/// Matches reference defaults d = 5, sigma_color = sigma_space = 125 (spec 6.2 step 3).
Image bilateral_filter(const Image& image, int diameter = 5, float sigma_color = 125.0f,
                       float sigma_space = 125.0f);

}  // namespace tdf
