#include <tdf/core/error.h>
#include <tdf/loss/image_loss.h>
#include <tdf/loss/tactile_loss.h>

namespace tdf {

// Vec3f is three packed floats, so a Vec3f array is a float array of 3 * count values.
static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be tightly packed");

TactileGuidanceMetric parse_tactile_guidance_metric(const std::string& text, const std::string& what) {
    if (text == "mse") return TactileGuidanceMetric::Mse;
    if (text == "cosine") return TactileGuidanceMetric::Cosine;
    throw_error("{}: unknown tactile guidance metric '{}' (expected mse or cosine)", what, text);
}

double tactile_matching_loss(const Vec3f* pred, const Vec3f* target, std::size_t count, Vec3f* grad,
                             float weight) {
    return cosine_loss(pred, target, count, grad, weight);
}

double tactile_guidance_loss(TactileGuidanceMetric metric, const Vec3f* pred, const Vec3f* refined,
                             std::size_t count, Vec3f* grad, float weight) {
    if (metric == TactileGuidanceMetric::Cosine) return cosine_loss(pred, refined, count, grad, weight);
    return mse_loss(reinterpret_cast<const float*>(pred),
                    reinterpret_cast<const float*>(refined),
                    3 * count,
                    reinterpret_cast<float*>(grad),
                    weight);
}

double masked_tactile_guidance_loss(TactileGuidanceMetric metric, const Vec3f* pred, const Vec3f* refined,
                                    const float* mask, std::size_t count, Vec3f* grad, float weight) {
    if (metric == TactileGuidanceMetric::Cosine) return masked_cosine_loss(pred, refined, mask, count, grad, weight);
    return masked_mse_loss(reinterpret_cast<const float*>(pred), reinterpret_cast<const float*>(refined), mask, 3,
                           count, reinterpret_cast<float*>(grad), weight);
}

}  // namespace tdf
