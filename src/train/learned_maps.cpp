#include <tdf/train/learned_maps.h>

#include <tdf/core/error.h>
#include <tdf/core/image_ops.h>
#include <tdf/core/parallel.h>
#include <tdf/core/release.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace tdf {

namespace {
constexpr std::size_t kTexelGrain = 8192;
}  // namespace

LearnedMaps::LearnedMaps(const TexelAtlas& atlas)
    : m_atlas(&atlas),
      m_residual(atlas.covered_count() * kResidualPerTexel, 0.0f),
      m_field_outputs(atlas.covered_count()),
      m_albedo(Image(atlas.size, atlas.size, 3, 0.5f)),
      m_normal(Image(atlas.size, atlas.size, 3, 0.0f)) {
    for (FieldOutputs& o : m_field_outputs) o = FieldOutputs{{0.5f, 0.5f, 0.5f}, {0, 0, 1}, {0, 0}};
}

void LearnedMaps::evaluate_field(const TextureField& field, bool keep_encodings) {
    if (keep_encodings) {
        field.evaluate(m_atlas->points.data(), m_atlas->points.size(), m_field_outputs.data(), m_cache);
    } else {
        m_cache.clear();  // 128 bytes a texel: kept only for a field_backward() to follow
        field.evaluate(m_atlas->points.data(), m_atlas->points.size(), m_field_outputs.data());
    }
}

void LearnedMaps::set_residual_to(const Image& albedo, const Image& normal) {
    const TexelAtlas& a = *m_atlas;
    TDF_CHECK(albedo.width() == a.size && normal.width() == a.size && albedo.channels() == 3 && normal.channels() == 3);
    parallel_for(a.covered_count(), kTexelGrain, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = a.texels[k];
            float* r = m_residual.data() + k * kResidualPerTexel;
            for (int c = 0; c < 3; ++c) {
                r[c] = albedo.data()[3 * t + std::size_t(c)] - m_field_outputs[k].albedo[c];
                r[3 + c] = normal.data()[3 * t + std::size_t(c)] - m_field_outputs[k].normal[c];
            }
        }
    });
}

void LearnedMaps::set_albedo_bounds(Image low, Image high) {
    const int size = m_atlas->size;
    TDF_CHECK(low.empty() == high.empty());
    TDF_CHECK(low.empty() || (low.width() == size && low.height() == size && low.channels() == 3 &&
                              high.width() == size && high.height() == size && high.channels() == 3));
    m_albedo_low = std::move(low);
    m_albedo_high = std::move(high);
}

void LearnedMaps::release_training_state() {
    release(m_residual);
    release(m_field_outputs);
    m_cache.clear();
    m_albedo_low = Image();
    m_albedo_high = Image();
}

void LearnedMaps::release_derived() {
    release(m_field_outputs);
    m_cache.clear();
    m_albedo.drop_levels();
    m_normal.drop_levels();
}

void LearnedMaps::restore_derived(const TextureField& field, bool keep_encodings) {
    m_field_outputs.resize(m_atlas->covered_count());
    evaluate_field(field, keep_encodings);
    restore_levels();
}

void LearnedMaps::restore_levels() {
    m_albedo.restore_levels();
    m_normal.restore_levels();
}

void LearnedMaps::update() {
    const TexelAtlas& a = *m_atlas;
    TDF_CHECK_EQ(m_residual.size(), a.covered_count() * kResidualPerTexel);
    const bool bounded = !m_albedo_low.empty();
    // Composed into the textures' own level 0 (one copy of each map), then their mips rebuilt.
    Image& albedo_level0 = m_albedo.base_level();
    Image& normal_level0 = m_normal.base_level();
    parallel_for(a.covered_count(), kTexelGrain, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = a.texels[k];
            float* r = m_residual.data() + k * kResidualPerTexel;
            for (int c = 0; c < 3; ++c) {
                const std::size_t i = 3 * t + std::size_t(c);
                float albedo = m_field_outputs[k].albedo[c] + r[c];
                if (bounded && (albedo < m_albedo_low.data()[i] || albedo > m_albedo_high.data()[i])) {
                    // Projected gradient descent: the residual is the optimizer's state, so it
                    // moves onto the bound with the map.
                    albedo = std::clamp(albedo, m_albedo_low.data()[i], m_albedo_high.data()[i]);
                    r[c] = albedo - m_field_outputs[k].albedo[c];
                }
                albedo_level0.data()[i] = albedo;
                normal_level0.data()[3 * t + std::size_t(c)] = m_field_outputs[k].normal[c] + r[3 + c];
            }
        }
    });
    a.fill_gutter(albedo_level0);
    a.fill_gutter(normal_level0);
    m_albedo.rebuild_levels();
    m_normal.rebuild_levels();
}

Image LearnedMaps::export_albedo() const {
    Image out = m_albedo.level(0);
    for (float& v : out.values()) v = std::clamp(v, 0.0f, 1.0f);
    return out;
}

Image LearnedMaps::export_normal() const {
    Image out = m_normal.level(0);
    for (std::size_t p = 0; p < out.pixel_count(); ++p) {
        float* n = out.data() + 3 * p;
        const Vec3f u = safe_normalize(Vec3f{n[0], n[1], n[2]});
        n[0] = u.x, n[1] = u.y, n[2] = u.z;
    }
    return out;
}

namespace {
const std::vector<float> kStepTent = {0.25f, 0.5f, 0.25f};
}  // namespace

bool LearnedMaps::backward(Image& d_albedo, Image& d_normal, std::vector<float>* d_residual,
                           std::vector<FieldOutputGrads>* d_field) const {
    const TexelAtlas& a = *m_atlas;
    TDF_CHECK(d_albedo.channels() >= 3 && d_normal.channels() >= 3);
    a.fold_gutter_gradient(d_albedo);
    a.fold_gutter_gradient(d_normal);
    if (d_residual) add_residual_gradient(d_albedo, d_normal, *d_residual);
    if (d_field) d_field->assign(a.covered_count(), FieldOutputGrads{});
    const std::size_t ca = std::size_t(d_albedo.channels()), cn = std::size_t(d_normal.channels());
    // dL/d(residual) of a texel is its map gradient (r enters the map with weight 1): finite
    // exactly when channels 0-2 of both maps are, at every covered texel.
    std::atomic<bool> finite{true};
    parallel_for(a.covered_count(), kTexelGrain, [&](std::size_t begin, std::size_t end) {
        bool chunk_finite = true;
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = a.texels[k];
            const float* ga = d_albedo.data() + ca * t;
            const float* gn = d_normal.data() + cn * t;
            for (int c = 0; c < 3; ++c) chunk_finite = chunk_finite && std::isfinite(ga[c]) && std::isfinite(gn[c]);
            if (d_field) {
                FieldOutputGrads& g = (*d_field)[k];
                g.d_albedo = {ga[0], ga[1], ga[2]};
                g.d_normal = {gn[0], gn[1], gn[2]};
            }
        }
        if (!chunk_finite) finite = false;
    });
    return finite;
}

void LearnedMaps::add_residual_gradient(const Image& d_albedo, const Image& d_normal,
                                        std::vector<float>& d_residual) const {
    const TexelAtlas& a = *m_atlas;
    if (d_residual.empty()) d_residual.assign(m_residual.size(), 0.0f);
    TDF_CHECK_EQ(d_residual.size(), m_residual.size());
    const std::size_t ca = std::size_t(d_albedo.channels()), cn = std::size_t(d_normal.channels());
    parallel_for(a.covered_count(), kTexelGrain, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = a.texels[k];
            float* dr = d_residual.data() + k * kResidualPerTexel;
            const float* ga = d_albedo.data() + ca * t;
            const float* gn = d_normal.data() + cn * t;
            for (int c = 0; c < 3; ++c) {
                dr[c] += ga[c];
                dr[3 + c] += gn[c];
            }
        }
    });
}

void LearnedMaps::jacobi_step(Image& d_albedo, const Image& d_normal, float step, int smoothing) {
    const TexelAtlas& a = *m_atlas;
    TDF_CHECK(d_albedo.channels() == 4 && d_normal.channels() == 4);
    // Views read the albedo through mip levels above 0, whose adjoint hands each 2x2 (4x4, ...)
    // block of texels one gradient and one curvature: unsmoothed, the step would move blocks
    // together and print their edges into level 0. Each pass of the symmetric [1 2 1] / 4 tent
    // (zero outside the map: the gutter holds no gradient after backward()) spreads gradient and
    // curvature alike, so the step stays the coverage-weighted mean of what nearby pixels ask.
    // The normal map is left alone: tactile patches read it near level 0, and per-part gating
    // (docs/multi-part-textures.md) must not reach across a part's boundary.
    // In place (convolve_separable allows it): no second 4-channel image, 16 bytes a texel.
    for (int pass = 0; pass < smoothing; ++pass) convolve_separable(d_albedo, d_albedo, kStepTent, Addressing::Border);
    // Damping: a texel seen by a tenth of the typical hit moves by at most about a tenth as much.
    const auto damping = [&](const Image& d) {
        double sum = 0;
        std::size_t seen = 0;
        for (std::size_t k = 0; k < a.covered_count(); ++k) {
            const float c = d.data()[4 * std::size_t(a.texels[k]) + 3];
            if (c > 0.0f) sum += c, ++seen;
        }
        return seen ? float(0.1 * sum / double(seen)) : 1.0f;
    };
    const float la = damping(d_albedo), ln = damping(d_normal);
    parallel_for(a.covered_count(), kTexelGrain, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = a.texels[k];
            float* r = m_residual.data() + k * kResidualPerTexel;
            const float* ga = d_albedo.data() + 4 * t;
            const float* gn = d_normal.data() + 4 * t;
            if (ga[3] > 0.0f)
                for (int c = 0; c < 3; ++c) r[c] -= step * ga[c] / (ga[3] + la);
            if (gn[3] > 0.0f)
                for (int c = 0; c < 3; ++c) r[3 + c] -= step * gn[c] / (gn[3] + ln);
        }
    });
}

void LearnedMaps::field_backward(const TextureField& field, const std::vector<FieldOutputGrads>& d_field,
                                 std::vector<float>& gradient) const {
    TDF_CHECK_EQ(d_field.size(), m_atlas->covered_count());
    field.backward(m_atlas->points.data(), d_field.data(), d_field.size(), gradient, m_cache);
}

}  // namespace tdf
