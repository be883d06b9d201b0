// Refinement's backward and update: the hits' gradients through the adjoint of the map lookups
// into the map gradients, then to the residual and the field, and the optimizer step.
// Reads: Batch::grads, curvature and lookups, the learned maps, the field cache.
// Writes: Batch's map gradients, the field gradient and (Adam's residual step) the residual's,
// all checked finite, and after
// update() the field, the residual and the maps.
#include "trainer_impl.h"

#include <tdf/core/error.h>

#include <cmath>

namespace tdf {

using namespace trainer_detail;

// ---- 5. Backward to the parameters ----------------------------------------------------------
// The map gradients hold no memory between iterations: an empty one is allocated (zero) by the
// first scatter into it.
void Trainer::begin_map_gradients() {
    m_batch->albedo_gradient.release();
    m_batch->normal_gradient.release();
}

void Trainer::reset_map_gradient(int map) {
    Batch& b = *m_batch;
    MipGradient& gradient = map == 0 ? b.albedo_gradient : b.normal_gradient;
    if (gradient.empty()) gradient.reset(map == 0 ? m_maps->albedo() : m_maps->normal(), 4);
}

// The adjoint of the map lookups: each hit's gradient goes to the texels it blended. Albedo and
// normal maps are independent; each texel gets its hits' sums in hit order (the same bits on any
// thread count). A half-iteration holds only patches or only views, so one map takes all its hits:
// they go in blocks, the taps of a block computed in parallel, then added by bands of texels in
// parallel (MipGradient::add_band), which keeps each texel's order.
// Channel 3 accumulates the hits' loss curvature through the same taps (the Jacobi step).
void Trainer::scatter_map_gradients() {
    Batch& b = *m_batch;
    const std::size_t n = b.hit_pixel.size();
    const MipTexture& albedo = m_maps->albedo();
    const std::size_t patch_hits = b.patch_hit_count;
    constexpr std::size_t kBlock = 1 << 14;
    // Any band count gives the same bits; one per thread keeps each thread to one pass over a block.
    const int band_count = std::max(1, ThreadLimit::current());
    b.scatter_taps.resize(kBlock);
    b.scatter_values.resize(kBlock);
    for (int map = 0; map < 2; ++map) {
        MipGradient& target = map == 0 ? b.albedo_gradient : b.normal_gradient;
        // Patches are hits [0, patch_hits) and send normal gradients; views send albedo ones.
        const std::size_t first = map == 0 ? patch_hits : 0, last = map == 0 ? n : patch_hits;
        if (first >= last) continue;
        reset_map_gradient(map);
        const MipGradient::Bands bands = target.bands(band_count);
        for (std::size_t block = first; block < last; block += kBlock) {
            const std::size_t count = std::min(kBlock, last - block);
            parallel_for(count, 1024, [&](std::size_t begin, std::size_t end) {
                for (std::size_t i = begin; i < end; ++i) {
                    const std::size_t q = block + i;
                    const FieldOutputGrads& g = b.grads[q];
                    const Vec3f d = map == 0 ? g.d_albedo : normalize_backward(b.raw_normal[q], g.d_normal, 1e-10f);
                    b.scatter_values[i] = {d.x, d.y, d.z, b.curvature[q]};
                    const auto& v = b.scatter_values[i];
                    if (v[0] == 0.0f && v[1] == 0.0f && v[2] == 0.0f && v[3] == 0.0f)
                        b.scatter_taps[i].count = 0;
                    else
                        albedo.taps(b.lookup_uv[q], b.lookup_lod[q], -1, b.scatter_taps[i]);
                }
            });
            parallel_for(std::size_t(band_count), 1, [&](std::size_t band_begin, std::size_t band_end) {
                for (std::size_t band = band_begin; band < band_end; ++band)
                    for (std::size_t i = 0; i < count; ++i)
                        if (b.scatter_taps[i].count > 0)
                            target.add_band(b.scatter_taps[i], b.scatter_values[i].data(), bands, int(band));
            });
        }
    }
}

void Trainer::backward(int i) {
    Batch& b = *m_batch;
    const std::size_t n = b.hit_pixel.size();
    std::fill(m_gradient.begin(), m_gradient.end(), 0.0f);
    if (!texture_space()) {
        m_field->backward(b.points.data(), b.grads.data(), n, m_gradient, b.field_cache);
        for (float g : m_gradient)
            if (!std::isfinite(g)) throw_error("iteration {}: the field gradient is not finite; the field was not updated", i);
        return;
    }
    // The hits were scattered into the map gradients view by view (scatter_map_gradients).
    for (int map = 0; map < 2; ++map) reset_map_gradient(map);  // a map no hit reached: zero
    b.albedo_gradient.collapse();
    b.normal_gradient.collapse();
    // Only Adam steps along the residual's gradient; the Jacobi step reads the map gradients
    // (gradient() derives the residual's from them on request).
    if (m_residual_adam) m_residual_gradient.assign(m_maps->residual().size(), 0.0f);
    const bool finite = m_maps->backward(b.albedo_gradient.level0(), b.normal_gradient.level0(),
                                         m_residual_adam ? &m_residual_gradient : nullptr,
                                         m_config.refine_grid ? &b.texel_grads : nullptr);
    m_map_gradients_unstepped = true;
    if (m_config.refine_grid) m_maps->field_backward(*m_field, b.texel_grads, m_gradient);
    if (!finite) throw_error("iteration {}: the map gradient is not finite; the maps were not updated", i);
    for (float g : m_gradient)
        if (!std::isfinite(g)) throw_error("iteration {}: the field gradient is not finite; the field was not updated", i);
}

// ---- 6. The Adam step (and, texture evaluation, the maps it changed) ------------------------
void Trainer::update(int i) {
    if (!texture_space()) {
        m_adam->step(m_field->parameters(), m_gradient);
        return;
    }
    (void)i;
    m_map_gradients_unstepped = false;  // the Jacobi step smooths the albedo's gradient in place
    if (m_config.residual_optimizer == "jacobi")
        m_maps->jacobi_step(m_batch->albedo_gradient.level0(), m_batch->normal_gradient.level0(), m_config.residual_step,
                            m_config.residual_step_smoothing);
    else
        m_residual_adam->step(m_maps->residual(), m_residual_gradient);
    if (m_config.refine_grid) {
        m_adam->step(m_field->parameters(), m_gradient);
        m_maps->evaluate_field(*m_field, m_config.refine_grid);
    }
    m_maps->update();
    begin_map_gradients();  // stepped on: not needed again before the next iteration's scatter
}

}  // namespace tdf
