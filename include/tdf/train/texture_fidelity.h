#pragma once
/// Texture-space fidelity of learned maps against known targets, texel by texel over the texels
/// the atlas covers: the measures of issue 10 (goals 1 and 2), computed the way
/// ../shared/tools/check_texture_fidelity.py computes them, so tests, the run report and the
/// independent script agree.
#include <tdf/core/image.h>
#include <tdf/core/config.h>

#include <cstdint>
#include <vector>

namespace tdf {

struct GBuffer;

struct TextureFidelity {
    double albedo_psnr = 0;          ///< dB, full band
    double albedo_psnr_lowpass = 0;  ///< dB after a Gaussian of `lowpass_sigma` texels on both maps
    double albedo_hf_ratio = 0;      ///< mean |finite difference| learned / target (> 1 speckle, < 1 blur)
    /// Mean |finite difference| of learned - target albedo over texels whose target relief is flat
    /// (tactile normal steeper than 1 degree nowhere within 8 texels), and the same measure of the
    /// target albedo there: refinement must not add detail where there is no relief.
    double albedo_added_hf_flat = 0;
    double albedo_hf_flat = 0;
    double flat_fraction = 0;  ///< fraction of compared texels that count as flat
    double normal_mean_cos = 0;
    double normal_p10_cos = 0;
    double normal_hf_ratio = 0;
    double coverage = 0;  ///< fraction of texels compared
    Json to_json() const;
};

/// Compares learned maps with targets of the same size (RGB; normals in [-1, 1], renormalised
/// here) over texels with `covered[t]` true. Either normal image may be empty (no normal
/// measures). `lowpass_sigma` in texels (the 2).
TextureFidelity measure_texture_fidelity(const Image& albedo, const Image& albedo_target, const Image& normal,
                                         const Image& normal_target, const std::vector<std::uint8_t>& covered,
                                         float lowpass_sigma = 2.0f);

/// Seams as a viewer sees them (issue 10 goal 4): the mean |difference| (summed over channels)
/// of an image between horizontally or vertically neighbouring surface pixels of a traced view,
/// split into pairs whose UVs jump (they differ from what the ray differentials predict by more
/// than 8 pixels' worth plus two texels of a `map_size` map: the two pixels lie on different
/// charts) and pairs inside a chart; pairs across a depth jump of more than 1 % (occlusion
/// edges) count as neither. Accumulates over views; `ratio()` is seam / interior.
struct SeamJump {
    double seam_sum = 0, interior_sum = 0;
    std::size_t seam_pairs = 0, interior_pairs = 0;
    void add(const GBuffer& g, const Image& image, int map_size);
    double seam() const { return seam_pairs ? seam_sum / double(seam_pairs) : 0.0; }
    double interior() const { return interior_pairs ? interior_sum / double(interior_pairs) : 0.0; }
    double ratio() const { return interior() > 0 ? seam() / interior() : 0.0; }
};

}  // namespace tdf
