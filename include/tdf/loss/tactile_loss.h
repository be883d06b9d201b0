#pragma once
/// Tactile loss terms on patch view-space shading normals (spec 5.3, 5.5). Same conventions as
/// image_loss.h (value returned unweighted, `weight * gradient` added to `grad`).
#include <tdf/core/vec.h>

#include <cstddef>
#include <string>

namespace tdf {

/// How the tactile-guidance term compares the rendered normals with the refined ones.
enum class TactileGuidanceMetric {
    Mse,     ///< Matches reference: mean squared error over all values (spec 5.5, 13.4)
    Cosine,  ///< the paper's 1 - cos (spec 13.4)
};

/// Parses "mse" / "cosine"; throws tdf::Error naming `what` otherwise.
TactileGuidanceMetric parse_tactile_guidance_metric(const std::string& text, const std::string& what);

/// Tactile matching (spec 5.3): 1 - mean cos(pred, target) over `count` patch pixels.
double tactile_matching_loss(const Vec3f* pred, const Vec3f* target, std::size_t count, Vec3f* grad = nullptr,
                             float weight = 1.0f);

/// Tactile guidance (spec 5.5): `metric` between the rendered patch normals and the guidance
/// backend's refined normals (both in [-1,1], background 0).
double tactile_guidance_loss(TactileGuidanceMetric metric, const Vec3f* pred, const Vec3f* refined,
                             std::size_t count, Vec3f* grad = nullptr, float weight = 1.0f);

/// Multi-part tactile guidance (spec 5.5, 7.3): tactile_guidance_loss of (mask x pred,
/// mask x refined), one mask value per pixel, the mean over all `count` pixels (the value of a
/// cosine term counts pixels outside the mask as cos 0, as the reference's masked terms do).
double masked_tactile_guidance_loss(TactileGuidanceMetric metric, const Vec3f* pred, const Vec3f* refined,
                                    const float* mask, std::size_t count, Vec3f* grad = nullptr, float weight = 1.0f);

}  // namespace tdf
