#pragma once
/// The part-label head of a multi-part run (spec 7.3, for any number of parts): N logits
/// z = W e + b over the field's hash-grid encoding e of a surface point, trained with softmax
/// cross-entropy against the segmentation's part. It shares the field's grid (the label loss
/// reaches the grid entries, as the reference's label channels do) but has its own N x F + N
/// parameters, because the field's built-in label rows are fixed at 2 (TextureField::kOutputs).
/// Deterministic: sums run in fixed chunks and per-level point order, as TextureField::backward.
#include <tdf/core/vec.h>
#include <tdf/field/texture_field.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace tdf {

/// Softmax cross-entropy of one point: returns -log softmax(z)[label] for `count` logits `z`
/// (computed with the max subtracted, finite for any finite logits) and, when `d_logits` is
/// given, writes scale x (softmax(z) - onehot(label)) to it (the gradient times `scale`).
double softmax_cross_entropy(const float* logits, int count, int label, float scale, float* d_logits);

class PartLabelHead {
public:
    /// `parts` >= 2 logits over `features` encoding values; weights and biases initialised
    /// U(-1/sqrt(F), 1/sqrt(F)) (PyTorch Linear) from `seed`.
    PartLabelHead(int parts, int features, std::uint64_t seed);

    int part_count() const { return m_parts; }
    int feature_count() const { return m_features; }
    /// W (parts x features, row-major) then b (parts).
    std::vector<float>& parameters() { return m_parameters; }
    const std::vector<float>& parameters() const { return m_parameters; }

    /// The logits at `n` world points of `field`'s grid: n x parts, point-major.
    void logits(const TextureField& field, const Vec3f* points, std::size_t n, std::vector<float>& out) const;
    /// argmax of the logits per point (ties: the lower part).
    std::vector<int> predict(const TextureField& field, const Vec3f* points, std::size_t n) const;

    /// weight x the mean cross-entropy over the points whose label is >= 0 (others are skipped;
    /// 0 when none is labelled). Adds its gradient with respect to parameters() to
    /// `head_gradient` (resized to parameters().size() and zeroed when its size differs) and,
    /// when `field_gradient` is given (field.parameter_count() values), with respect to the
    /// field's grid entries. `labelled` (optional) receives the number of labelled points.
    double loss_and_gradient(const TextureField& field, const Vec3f* points, const int* labels, std::size_t n,
                             float weight, std::vector<float>& head_gradient, std::vector<float>* field_gradient,
                             std::size_t* labelled = nullptr) const;

private:
    int m_parts;
    int m_features;
    std::vector<float> m_parameters;
};

}  // namespace tdf
