#pragma once
/// Weight-free segmentation of a base albedo into colour regions: k-means in CIELAB (a
/// perceptual space: equal distances look about equally different), K given or chosen by the
/// mean silhouette, then spatial regularisation by rounds of neighbourhood majority voting.
/// Used by the `colour` parts source (part_segmentation.h) on the atlas texels.
#include <tdf/core/vec.h>

#include <cstdint>
#include <string>
#include <vector>

namespace tdf {

/// sRGB in [0,1] (gamma-encoded, D65) to CIELAB (L in [0, 100], a and b about [-128, 127]).
Vec3f srgb_to_lab(Vec3f rgb);

struct ColourClusteringOptions {
    int k = 0;                      ///< clusters; 0 = choose in [2, k_max] by the largest mean silhouette
    int k_max = 6;                  ///< [2, 16]
    int iterations = 30;            ///< Lloyd iterations (stops earlier when no assignment changes)
    std::uint64_t seed = 0;         ///< k-means++ seeding and the silhouette subsample
    int sample_limit = 20000;       ///< k-means runs on at most this many samples (every sample is assigned)
    int silhouette_samples = 1500;  ///< points used for the silhouette when choosing K
};

/// One colour cluster.
struct ColourCluster {
    Vec3f lab;          ///< mean CIELAB of its samples
    Vec3f rgb;          ///< mean sRGB in [0, 1]
    double weight = 0;  ///< sum of the sample weights assigned to it
};

struct ColourClustering {
    std::vector<ColourCluster> clusters;  ///< sorted by weight, largest first
    std::vector<int> label;               ///< per sample, index into `clusters`
    std::vector<double> silhouette;       ///< mean silhouette for K = 2..k_max when K was chosen (else empty)
    int distinct_colours = 0;             ///< distinct 8-bit sRGB colours among the samples
};

/// Clusters `rgb` (sRGB in [0,1], one per sample, with non-negative `weight`s, e.g. texel or
/// surface area). Throws tdf::Error (naming `where`) when there are fewer samples than clusters,
/// or when `k` exceeds the number of distinct colours present ("K larger than the colours
/// present"). With k = 0 a K above the distinct colour count is never tried. Deterministic for
/// a given seed, on any thread count.
ColourClustering cluster_colours(const std::vector<Vec3f>& rgb, const std::vector<float>& weight,
                                 const ColourClusteringOptions& options, const std::string& where);

/// Majority smoothing on a graph: `rounds` times, every node takes the label with the largest
/// summed edge weight among its neighbours plus itself (its own vote weighted `self_weight`);
/// ties keep the current label. Nodes with label < 0 neither vote nor change. `neighbours[i]`
/// lists (node, weight) pairs. Synchronous updates, so the result is order-independent.
void majority_smooth(std::vector<int>& label,
                     const std::vector<std::vector<std::pair<int, float>>>& neighbours, int rounds,
                     float self_weight = 1.f);

}  // namespace tdf
