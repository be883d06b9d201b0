#pragma once
/// Part masks gating the tactile terms of a multi-part run (spec 7.3, 5.3, 5.5;
/// docs/multi-part-textures.md): every patch pixel belongs to the part the label head predicts at
/// the atlas texel its lookup lands on; part k's tactile matching and tactile guidance terms see only
/// its own pixels (the reference's M_k n_hat, M_k target), with part k's own weights, prompt and
/// guidance backend (whose exemplars are part k's tactile maps). One normal map holds all parts.
///
/// Two masks per pixel. Matching: the part of the texel the lookup lands on (its target, the
/// composed one, already blends the boundary). Guidance: the part only when EVERY texel the
/// pixel's filtered lookup reads (bilinear at level 0, trilinear further away) is that part's,
/// else none: a refined target of one material then never reaches the other's texels through
/// the lookup's adjoint (with the plain mask, a tilted part-1 target moved other parts' texels up
/// to 5 texels away at grazing patch angles; with this one no farther than the boundary band).
#include <tdf/core/config.h>
#include <tdf/core/vec.h>
#include <tdf/render/texture.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/loss/tactile_loss.h>
#include <tdf/train/loss_log.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace tdf {

/// `parts.list[i].guidance`: the part's own tactile settings. Negative weights and an empty
/// backend mean "the run's" (weights.tactile_refine, weights.tactile_guidance, guidance.tactile).
struct PartGuidanceSettings {
    std::string backend;          ///< tactile guidance backend; "none" = no guidance on this part
    float matching_weight = -1;   ///< the part's tactile matching weight in refinement
    float guidance_weight = -1;   ///< the part's tactile guidance weight
    double strength = -1;         ///< the part's tactile request strength (< 0: kTactileGuidanceStrength)
    Json backend_config;          ///< replaces guidance.<backend> for this part (null: the run's)
    /// Reads {"backend", "matching_weight", "weight", "strength", "config"}; unknown keys and bad
    /// values are one line naming `where` and the key.
    static PartGuidanceSettings from_json(const Json& guidance, const std::string& where);
};

/// One part as the trainer gates it.
struct PartGuidance {
    std::string name;
    std::string prompt;             ///< tactile request prompt; "" = the reference's "sks normal map"
    PartGuidanceSettings settings;
    std::unique_ptr<GuidanceBackend> backend;  ///< nullptr: no tactile guidance on this part
};

/// The patch batch as the gated terms see it: P patches of R x R pixels, image after image.
struct GatedPatches {
    int patches = 0, resolution = 0;
    const Vec3f* pred = nullptr;     ///< rendered view-space normals (0 off the surface)
    const Vec3f* target = nullptr;   ///< matching targets (the composed tactile target)
    const std::int16_t* part = nullptr;  ///< per pixel the matching part (part_at), -1 off the surface
    const std::int16_t* guidance_part = nullptr;  ///< per pixel the guidance part (pure_part), -1 = none
    Vec3f* grad = nullptr;           ///< dL/d(pred), accumulated into
    /// Appends patch k's guidance images to `request` with coverage x `mask` (R x R values) as
    /// its mask (the trainer's frames and surface data).
    std::function<void(GuidanceRequest& request, int k, const float* mask)> add_patch;
};

/// What the phase asks of the gated terms.
struct GatedPhase {
    int iteration = 0;
    float matching_weight = 0;  ///< the run's tactile matching weight this iteration (0 = off)
    bool guidance = false;      ///< tactile guidance this iteration
    float guidance_weight = 0;  ///< the run's tactile guidance weight
    TactileGuidanceMetric metric = TactileGuidanceMetric::Cosine;
    std::uint64_t seed = 0;
    float pixels_per_texel = 0;
};

class PartGate {
public:
    /// Gates over a size x size atlas; one PartGuidance per part (>= 2). No labels yet.
    PartGate(int size, std::vector<PartGuidance> parts);

    /// The labels the masks come from: size x size (i * size + j, -1 = none), gutter texels
    /// labelled with the part of the texel they copy (TexelAtlas::source).
    void set_texel_part(std::vector<int> texel_part);
    bool has_labels() const { return !m_texel_part.empty(); }
    /// Replaces the parts' settings and backends (same count).
    void set_parts(std::vector<PartGuidance> parts);

    int part_count() const { return int(m_parts.size()); }
    const PartGuidance& part(int k) const { return m_parts[std::size_t(k)]; }
    const std::vector<int>& texel_part() const { return m_texel_part; }
    /// Whether any part has a guidance backend with a positive weight (given the run's weight).
    bool has_guidance(float run_weight) const;

    /// The part at atlas coordinate `uv` (v up): the label of the texel it falls in (the hard
    /// mask of the reference's argmax), -1 outside any part.
    int part_at(Vec2f uv) const;

    /// The part whose texels hold every tap of `taps` (a lookup into a texture of the atlas's size,
    /// weights > 0), -1 when the taps read texels of two parts or of none. Coarser levels count a
    /// texel as a part's only when all level-0 texels under it are.
    int pure_part(const TrilinearTaps& taps) const;

    /// Part k's tactile matching weight / guidance weight given the run's.
    float matching_weight(int k, float run_weight) const;
    float guidance_weight(int k, float run_weight) const;

    /// The gated tactile terms: per part `tactile_matching_<name>` and `tactile_guidance_<name>`
    /// into `record` (weighted, as every term), gradients into patches.grad; frames of every
    /// guidance call go to `frames` when set (request, result, part index).
    void tactile_terms(const GatedPatches& patches, const GatedPhase& phase, LossRecord& record,
                       const std::function<void(const GuidanceRequest&, const GuidanceResult&, int)>& frames = {});

private:
    std::vector<int> m_texel_part;
    std::vector<std::vector<int>> m_pure;  // per mip level (MipTexture sizes): the part, -1 = mixed or none
    int m_size;
    std::vector<PartGuidance> m_parts;
};

}  // namespace tdf
