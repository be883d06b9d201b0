#pragma once
/// Texture optimisation (Kwatra, Essa, Bobick & Kwatra 2005): refines a synthesised texture so
/// that every neighbourhood of it resembles a neighbourhood of the exemplars' textured regions.
///
/// Alternates two steps over overlapping square windows laid on a grid (every window/4 px; the
/// last, finest side at every pixel, so its per-pixel choice leaves no line pattern):
///  - E: for each output window, the nearest exemplar window (sum of squared differences after
///    removing both windows' means: heights matter by their shape, not their level), searched
///    with PatchMatch (Barnes et al. 2009: the previous match, the neighbours' matches shifted,
///    a shrinking random search, fresh random draws). Only windows lying at least
///    `min_coverage` in their exemplar's region are sources, so flat gel never comes back.
///  - M: every output pixel becomes the robust weighted mean (Kwatra's weight |x - z|^(r - 2),
///    r = 0.8) of the matched windows covering it, each shifted to the output window's mean;
///    the very last M step takes each pixel from its best-matching window instead (a mean of
///    disagreeing windows is smoother than any of them).
/// Window sides run coarse to fine (32, 16, 8 px), a few iterations each (8 at the coarsest
/// side, where the layout forms: after 4 its matching energy still fell 4 % per iteration, and
/// its windows, every 8 px, make an iteration a quarter of the finest side's cost). Overlapping
/// windows are averaged, so no cut line survives (unlike quilting's boundary cuts).
///
/// Reproducibility: window q of iteration i draws only from Rng::stream(seed, ...(i, q)) and
/// reads only the previous iteration's matches (Jacobi-style propagation), so the result is
/// the same on any thread count.
#include <tdf/core/image.h>

#include <cstdint>
#include <vector>

namespace tdf {

struct TextureOptimizationOptions {
    std::vector<int> windows{32, 16, 8};  ///< window sides, coarse to fine, each >= 4
    /// EM iterations per window side: iterations[k] for windows[k]; sides beyond the list take
    /// its last value (one value = every side). Each >= 1; at most one per side.
    std::vector<int> iterations{8, 4, 4};
    float min_coverage = 0.95f;           ///< source windows lie at least this much in the region
    bool tileable = true;                 ///< the output wraps around
    std::uint64_t seed = 42;
};

/// Refines `initial` (1 channel, e.g. a quilt of the exemplars) towards the exemplars (1
/// channel each; `masks`: 1 channel of each exemplar's size, empty = all of it). Throws
/// tdf::Error for invalid options or inputs.
Image optimize_texture(const std::vector<Image>& exemplars, const std::vector<Image>& masks, const Image& initial,
                       const TextureOptimizationOptions& options);

}  // namespace tdf
