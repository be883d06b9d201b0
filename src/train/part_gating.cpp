#include <tdf/train/part_gating.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/guidance/schedule.h>
#include <tdf/loss/image_loss.h>

#include <algorithm>
#include <cmath>

namespace tdf {

PartGuidanceSettings PartGuidanceSettings::from_json(const Json& guidance, const std::string& where) {
    PartGuidanceSettings s;
    if (guidance.is_null()) return s;
    if (!guidance.is_object()) throw_error("{}: must be an object", where);
    ConfigReader r(guidance, where);
    s.backend = r.get<std::string>("backend", "");
    const auto weight = [&](const char* key) {
        const float w = r.get<float>(key, -1.0f);
        if (r.has(key) && !(w >= 0.0f && std::isfinite(w)))
            throw_error("{}.{}: {} is not a finite weight >= 0", where, key, w);
        return w;
    };
    s.matching_weight = weight("matching_weight");
    s.guidance_weight = weight("weight");
    s.strength = r.get<double>("strength", -1.0);
    if (r.has("strength") && !(s.strength >= 0.0 && s.strength <= 1.0))
        throw_error("{}.strength: {} is not in [0, 1]", where, s.strength);
    if (r.has("config")) {
        s.backend_config = r.raw("config");
        if (!s.backend_config.is_object()) throw_error("{}.config: must be an object", where);
    }
    r.check_all_read();
    return s;
}

PartGate::PartGate(int size, std::vector<PartGuidance> parts) : m_size(size) {
    TDF_CHECK(size > 0);
    set_parts(std::move(parts));
}

void PartGate::set_parts(std::vector<PartGuidance> parts) {
    TDF_CHECK(!parts.empty() && parts.size() < 32768);
    TDF_CHECK(m_parts.empty() || parts.size() == m_parts.size());
    m_parts = std::move(parts);
}

void PartGate::set_texel_part(std::vector<int> texel_part) {
    TDF_CHECK(texel_part.size() == std::size_t(m_size) * std::size_t(m_size));
    for (int l : texel_part) TDF_CHECK(l < part_count());
    m_texel_part = std::move(texel_part);
    // Pure labels per level, over the texels each coarse texel's box filter reads (MipTexture:
    // level k+1 has max(1, floor(size_k / 2)) texels per axis; odd sizes read a third row).
    m_pure.assign(1, m_texel_part);
    for (int side = m_size; side > 1;) {
        const int next = std::max(1, side / 2);
        const std::vector<int>& fine = m_pure.back();
        std::vector<int> coarse(std::size_t(next) * std::size_t(next), -1);
        for (int y = 0; y < next; ++y)
            for (int x = 0; x < next; ++x) {
                const int y0 = y * side / next, y1 = std::min(side, ((y + 1) * side + next - 1) / next);
                const int x0 = x * side / next, x1 = std::min(side, ((x + 1) * side + next - 1) / next);
                int part = fine[std::size_t(y0) * std::size_t(side) + std::size_t(x0)];
                for (int v = y0; v < y1 && part >= 0; ++v)
                    for (int u = x0; u < x1; ++u)
                        if (fine[std::size_t(v) * std::size_t(side) + std::size_t(u)] != part) {
                            part = -1;
                            break;
                        }
                coarse[std::size_t(y) * std::size_t(next) + std::size_t(x)] = part;
            }
        m_pure.push_back(std::move(coarse));
        side = next;
    }
}

int PartGate::pure_part(const TrilinearTaps& taps) const {
    int part = -1;
    for (int i = 0; i < taps.count; ++i) {
        if (!(taps.weight[i] > 0.0f)) continue;
        TDF_CHECK(taps.level[i] >= 0 && std::size_t(taps.level[i]) < m_pure.size());
        const int p = m_pure[std::size_t(taps.level[i])][taps.texel[i]];
        if (p < 0 || (part >= 0 && p != part)) return -1;
        part = p;
    }
    return part;
}

bool PartGate::has_guidance(float run_weight) const {
    for (int k = 0; k < part_count(); ++k)
        if (m_parts[std::size_t(k)].backend && guidance_weight(k, run_weight) > 0) return true;
    return false;
}

int PartGate::part_at(Vec2f uv) const {
    TDF_CHECK(has_labels());
    // The texel the point falls in (UvRaster convention: row 0 at v = 1).
    const int col = std::clamp(int(std::floor(uv.x * float(m_size))), 0, m_size - 1);
    const int row = std::clamp(int(std::floor((1.0f - uv.y) * float(m_size))), 0, m_size - 1);
    return m_texel_part[std::size_t(row) * std::size_t(m_size) + std::size_t(col)];
}

float PartGate::matching_weight(int k, float run_weight) const {
    const float w = m_parts[std::size_t(k)].settings.matching_weight;
    return w >= 0 ? w : run_weight;
}

float PartGate::guidance_weight(int k, float run_weight) const {
    const float w = m_parts[std::size_t(k)].settings.guidance_weight;
    return w >= 0 ? w : run_weight;
}

void PartGate::tactile_terms(const GatedPatches& patches, const GatedPhase& phase, LossRecord& record,
                             const std::function<void(const GuidanceRequest&, const GuidanceResult&, int)>& frames) {
    const std::size_t patch_pixels = std::size_t(patches.resolution) * std::size_t(patches.resolution);
    const std::size_t n = std::size_t(patches.patches) * patch_pixels;
    if (n == 0) return;
    std::vector<float> mask(n);
    std::vector<Vec3f> refined;
    for (int k = 0; k < part_count(); ++k) {
        const PartGuidance& part = m_parts[std::size_t(k)];
        const auto fill_mask = [&](const std::int16_t* part_of) {
            std::size_t pixels = 0;
            for (std::size_t p = 0; p < n; ++p) {
                mask[p] = part_of[p] == k ? 1.0f : 0.0f;
                pixels += part_of[p] == k;
            }
            return pixels;
        };
        std::size_t pixels = fill_mask(patches.part);
        // The masked cosine terms count every pixel outside the mask as 1 - cos 0 (the reference's
        // 1 - mean cos(M n, M t)); the gradient is the same without that constant, and the part's
        // own share, sum over its pixels of (1 - cos) / all pixels, is what the log shows.
        const double outside = double(n - pixels) / double(n);
        // Part k's matching term, even when it has no pixels here (then 0, no gradient): the
        // loss log keeps the same terms every iteration.
        const float wm = matching_weight(k, phase.matching_weight);
        if (phase.matching_weight > 0 && wm > 0)
            record.terms["tactile_matching_" + part.name] =
                wm * std::max(0.0, masked_cosine_loss(patches.pred, patches.target, mask.data(), n, patches.grad, wm) -
                                       outside);  // >= 0: the difference only rounds below
        const float wg = guidance_weight(k, phase.guidance_weight);
        if (!phase.guidance || !part.backend || !(wg > 0)) continue;
        pixels = fill_mask(patches.guidance_part);
        if (pixels == 0) continue;
        const double guidance_outside = double(n - pixels) / double(n);
        // Part k's request: only the patches holding its pixels, the others' refined images stay 0.
        GuidanceRequest request;
        request.kind = GuidanceKind::Tactile;
        request.prompt = part.prompt.empty() ? "sks normal map" : part.prompt;  // spec 5.5
        request.strength = part.settings.strength >= 0 ? part.settings.strength : kTactileGuidanceStrength;
        request.iteration = phase.iteration;
        request.seed = phase.seed ^ (std::uint64_t(k) << 48);
        request.pixels_per_texel = phase.pixels_per_texel;
        std::vector<int> sent;
        for (int patch = 0; patch < patches.patches; ++patch) {
            const float* m = mask.data() + std::size_t(patch) * patch_pixels;
            if (std::none_of(m, m + patch_pixels, [](float v) { return v > 0.0f; })) continue;
            patches.add_patch(request, patch, m);
            sent.push_back(patch);
        }
        const GuidanceResult result = part.backend->refine(request);
        validate_result(request, result, part.backend->name() + " (part '" + part.name + "')");
        if (frames) frames(request, result, k);
        refined.assign(n, Vec3f{});
        for (std::size_t s = 0; s < sent.size(); ++s)
            std::copy_n(result.refined[s].data(), 3 * patch_pixels, &refined[std::size_t(sent[s]) * patch_pixels].x);
        const double value =
            masked_tactile_guidance_loss(phase.metric, patches.pred, refined.data(), mask.data(), n, patches.grad, wg);
        record.terms["tactile_guidance_" + part.name] =
            wg * (phase.metric == TactileGuidanceMetric::Cosine ? std::max(0.0, value - guidance_outside) : value);
    }
}

}  // namespace tdf
