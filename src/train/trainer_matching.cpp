// Matching phase (texture evaluation, iterations [0, init_iterations)): fits the hash grid to
// the targets laid over the atlas on a random sample of texels, with no rendering.
// Reads: the atlas, the albedo and tactile targets, the part labels (multi-part), the field.
// Writes: the field and (multi-part) the label head through their Adam steps, the loss record,
// StageTimes::matching; at the phase's end the maps (prepare_maps).
#include "trainer_impl.h"

#include <tdf/core/error.h>
#include <tdf/train/part_label_head.h>

#include <cmath>

namespace tdf {

using namespace trainer_detail;

namespace {

// Weight of the label cross-entropy (multi-part): the reference's lambda_label_field.
constexpr float kLabelWeight = 1.0f;

}  // namespace

// ---- Matching phase of the texture-space optimizer ------------------------------------------
// The targets are known per texel, so the grid is fitted to them directly on a random sample of
// texels each iteration (dense supervision, no rendering), and the residual takes what the grid
// cannot hold when the phase ends (prepare_maps).
LossRecord Trainer::fit_maps(int i) {
    const auto start = Clock::now();
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const TexelAtlas& atlas = *m_atlas;
    Rng rng = Rng::stream(m_seed, std::uint64_t(i));
    const std::size_t n = std::min<std::size_t>(std::size_t(cfg.fit_texels), atlas.covered_count());
    std::vector<std::uint32_t>& picked = b.fit_texels;
    picked.resize(n);
    if (n == atlas.covered_count()) {
        for (std::size_t k = 0; k < n; ++k) picked[k] = std::uint32_t(k);
    } else {
        for (std::size_t k = 0; k < n; ++k) picked[k] = std::uint32_t(rng.uniform_int(0, int(atlas.covered_count()) - 1));
    }
    b.points.resize(n);
    for (std::size_t k = 0; k < n; ++k) b.points[k] = atlas.points[picked[k]];
    b.outputs.resize(n);
    m_field->evaluate(b.points.data(), n, b.outputs.data(), b.field_cache);
    b.grads.assign(n, FieldOutputGrads{});

    const float wa = cfg.weights.texture_albedo, wt = cfg.weights.texture_tactile;
    const Image& albedo_target = this->albedo_target();
    const Image& tactile_target = this->tactile_target();
    std::vector<double> partial(chunk_count(n, kPixelGrain) * 2, 0.0);
    parallel_for(n, kPixelGrain, [&](std::size_t begin, std::size_t end) {
        double albedo_sum = 0, tactile_sum = 0;
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = atlas.texels[picked[k]];
            const float* ta = albedo_target.data() + 3 * t;
            const Vec3f target_normal{tactile_target.data()[3 * t], tactile_target.data()[3 * t + 1],
                                      tactile_target.data()[3 * t + 2]};
            const Vec3f e = b.outputs[k].albedo - Vec3f{ta[0], ta[1], ta[2]};
            albedo_sum += double(dot(e, e));
            // mean over texels x 3 channels of the squared error; mean over texels of 1 - cos.
            b.grads[k].d_albedo = e * (2.0f * wa / (3.0f * float(n)));
            const Vec3f p = b.outputs[k].normal;  // unit
            tactile_sum += 1.0 - double(dot(p, target_normal));
            b.grads[k].d_normal = normalize_backward(p, target_normal * (-wt / float(n)), 1e-12f);
        }
        const std::size_t c = begin / kPixelGrain;
        partial[2 * c] = albedo_sum;
        partial[2 * c + 1] = tactile_sum;
    });
    double albedo_sum = 0, tactile_sum = 0;
    for (std::size_t c = 0; c < partial.size() / 2; ++c) albedo_sum += partial[2 * c], tactile_sum += partial[2 * c + 1];
    LossRecord record;
    record.iteration = i;
    record.terms["texture_albedo"] = wa * albedo_sum / (3.0 * double(n));
    record.terms["texture_tactile"] = wt * tactile_sum / double(n);
    record.terms["total"] = record.terms["texture_albedo"] + record.terms["texture_tactile"];
    std::fill(m_gradient.begin(), m_gradient.end(), 0.0f);
    if (m_label_head) {
        record.terms["texture_label"] = fit_labels(n);
        record.terms["total"] += record.terms["texture_label"];
    }
    for (const auto& [name, value] : record.terms)
        if (!std::isfinite(value))
            throw_error("iteration {}: loss term '{}' is not finite ({}); the field was not updated", i, name, value);
    m_field->backward(b.points.data(), b.grads.data(), n, m_gradient, b.field_cache);
    for (float g : m_gradient)
        if (!std::isfinite(g)) throw_error("iteration {}: the field gradient is not finite; the field was not updated", i);
    for (float g : m_label_gradient)
        if (!std::isfinite(g)) throw_error("iteration {}: the label head gradient is not finite; nothing was updated", i);
    m_adam->step(m_field->parameters(), m_gradient);
    if (m_label_head) {
        m_label_adam->step(m_label_head->parameters(), m_label_gradient);
        m_gate_labels_stale = true;
    }
    ++m_iteration;
    if (m_iteration == cfg.init_iterations) prepare_maps();
    record.seconds = seconds_since(start);
    m_times.matching += record.seconds;
    return record;
}

// Multi-part: cross-entropy of the label head against the known part of each fit texel, weight
// 1 (the reference's lambda_label_field), mean over the texels that have a part.
double Trainer::fit_labels(std::size_t n) {
    const Batch& b = *m_batch;
    std::vector<int> labels(n);
    for (std::size_t k = 0; k < n; ++k) labels[k] = (*m_target.texel_parts)[m_atlas->texels[b.fit_texels[k]]];
    m_label_gradient.assign(m_label_head->parameters().size(), 0.0f);
    return m_label_head->loss_and_gradient(*m_field, b.points.data(), labels.data(), n, kLabelWeight, m_label_gradient,
                                           &m_gradient);
}

}  // namespace tdf
