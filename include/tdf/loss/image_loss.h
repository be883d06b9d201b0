#pragma once
/// Image and vector losses with their gradients (spec 5.2-5.5).
///
/// Conventions shared by every function here:
///  - inputs are flat float arrays: images interleaved (pixel-major, channels last, row 0 at
///    the top, several images back to back), vectors as Vec3f arrays;
///  - the return value is the loss itself (unweighted, in double);
///  - when `grad` is not null, `weight * dL/d(pred)` is ADDED to it (same layout as `pred`),
///    so several weighted terms accumulate into one upstream gradient buffer;
///  - sums run over fixed chunks reduced in chunk order: bit-identical on any thread count;
///  - only `pred` receives gradient (targets are constants, as in the reference).
#include <tdf/core/vec.h>

#include <cstddef>

namespace tdf {

/// Shape of a batch of equally sized interleaved images.
struct ImageBatchShape {
    int images = 1;
    int width = 0;
    int height = 0;
    int channels = 3;
    std::size_t pixels() const { return std::size_t(width) * std::size_t(height); }
    std::size_t values() const { return std::size_t(images) * pixels() * std::size_t(channels); }
};

/// Mean squared error over all `count` values (torch `F.mse_loss`, spec 5.2 init term and the
/// tactile-guidance MSE of spec 5.5).
double mse_loss(const float* pred, const float* target, std::size_t count, float* grad = nullptr,
                float weight = 1.0f);

/// mse_loss of (mask x pred, mask x target) over `count` vectors of `channels` values, one mask
/// value per vector (multi-part tactile guidance, spec 5.5): the mean runs over all values.
double masked_mse_loss(const float* pred, const float* target, const float* mask, int channels, std::size_t count,
                       float* grad = nullptr, float weight = 1.0f);

/// Mean absolute error over all `count` values (torch `F.l1_loss`; d|x|/dx at 0 is 0, like torch).
double l1_loss(const float* pred, const float* target, std::size_t count, float* grad = nullptr,
               float weight = 1.0f);

/// Mean-colour MSE (spec 5.2 refine term): per image and channel the spatial mean over all
/// pixels (background included), then the mean over images x channels of the squared
/// difference of those means.
double mean_colour_mse_loss(const float* pred, const float* target, const ImageBatchShape& shape,
                            float* grad = nullptr, float weight = 1.0f);

/// Cosine similarity of two 3-vectors as torch `F.cosine_similarity` (spec 5.3):
/// x.y / max(|x| |y|, eps). Zero vectors give 0.
float cosine_similarity(Vec3f x, Vec3f y, float eps = 1e-8f);

/// 1 - mean over `count` vectors of cosine_similarity(pred, target) (spec 5.3 tactile matching
/// and the paper's cosine tactile-guidance variant). Background pixels (zero vectors) count
/// in the mean with cos 0 and get (almost) no gradient.
double cosine_loss(const Vec3f* pred, const Vec3f* target, std::size_t count, Vec3f* grad = nullptr,
                   float weight = 1.0f);

/// Multi-part tactile matching term (spec 5.3): 1 - mean cos(mask * pred, mask * target) with a
/// per-vector mask (1 inside the part, 0 outside; fractional values are allowed).
double masked_cosine_loss(const Vec3f* pred, const Vec3f* target, const float* mask, std::size_t count,
                          Vec3f* grad = nullptr, float weight = 1.0f);

/// Structural term: 1 - mean SSIM (Wang et al. 2004; 11x11 Gaussian window, sigma 1.5, zero
/// padding to the same size, C1 = 0.01^2, C2 = 0.03^2 for values in [0,1]) over all images,
/// pixels and channels. It stands in for the reference's LPIPS-VGG term (spec 5.4), whose
/// network weights are not available here; like LPIPS it rewards matching local structure
/// rather than exact values. Allocates a few image-sized buffers per call.
double ssim_loss(const float* pred, const float* target, const ImageBatchShape& shape, float* grad = nullptr,
                 float weight = 1.0f);

}  // namespace tdf
