#pragma once
/// Texture-space fidelity of learned maps against known targets, texel by texel over the texels
/// the atlas covers: the measures of issue 10 (goals 1 and 2), computed the way
/// ../shared/tools/check_texture_fidelity.py computes them, so tests, the run report and the
/// independent script agree.
#include <tdf/core/image.h>
#include <tdf/core/config.h>
#include <tdf/mesh/uv_seams.h>

#include <cstdint>
#include <unordered_map>
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

/// The continuity (uv_seams.h) between any two triangles of a mesh, looked up per pixel pair.
/// Seams along creases sharper than `crease_degrees` (between the faces' normals) count as
/// `Apart`: there the surface turns a corner, and its colour and relief may change by design.
class MeshSeams {
public:
    explicit MeshSeams(const TriangleMesh& mesh, float crease_degrees = 30.0f);
    EdgeContinuity between(int triangle_a, int triangle_b) const;
    std::size_t seam_edges() const { return m_seam_edges; }
    std::size_t cone_edges() const { return m_cone_edges; }
    std::size_t crease_edges() const { return m_crease_edges; }

private:
    std::unordered_map<std::uint64_t, EdgeContinuity> m_edges;  ///< key: (min triangle, max triangle)
    std::size_t m_seam_edges = 0, m_cone_edges = 0, m_crease_edges = 0;
};

/// Seams as a viewer sees them (issue 10 goal 4), in a traced view: for every pair of
/// horizontally or vertically neighbouring surface pixels whose triangles meet at a `Seam` edge
/// (MeshSeams), the |difference| of the image (summed over channels) across it, against the mean
/// |difference| of the two steps before and the two after it along the same line, all inside one
/// chart (pairs without those four are skipped). The local baseline makes the measure compare a
/// seam with the surface beside it at the same distance, direction and foreshortening (a seam
/// seen near the silhouette spans many texels per pixel, as do its neighbours). Pairs across a
/// `Cone` edge are measured the same way but kept apart: there even the input's own texture changes
/// with the UV direction. Pairs across a depth jump of more than 1 % (occlusion edges) count
/// nowhere. Accumulates over views; `ratio()` is seam / baseline.
struct SeamJump {
    double seam_sum = 0, interior_sum = 0, cone_sum = 0, cone_interior_sum = 0;
    std::size_t seam_pairs = 0, cone_pairs = 0;
    void add(const GBuffer& g, const Image& image, const MeshSeams& seams);
    double ratio() const { return interior_sum > 0 ? seam_sum / interior_sum : 0.0; }
    double cone_ratio() const { return cone_interior_sum > 0 ? cone_sum / cone_interior_sum : 0.0; }
};

}  // namespace tdf
