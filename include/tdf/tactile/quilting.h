#pragma once
/// Image quilting (Efros & Freeman 2001) with minimum-error boundary cuts, as the reference's
/// step 2 (spec 6.3), made reproducible, parallel and optionally tileable.
///
/// Blocks of `block` pixels are laid on a grid with stride block - overlap, in raster order.
/// For each block every top-left position of every exemplar is a candidate; its error is the
/// mean squared difference to the already placed pixels under the block (all channels). The
/// candidate search evaluates all positions at once with FFT cross-correlations (exact up to
/// rounding). Candidates with zero error (a verbatim continuation) are skipped and one of those
/// with error < (1 + tolerance) * minimum is drawn uniformly; it is pasted with a
/// minimum-error boundary cut (dynamic programming, 8-neighbour paths) on every side that
/// overlaps placed pixels, optionally feathered.
///
/// Reproducibility: block (row, col) draws only from Rng::stream(seed, row * n + col), and
/// blocks whose footprints do not overlap are placed concurrently in dependency levels, which
/// gives exactly the raster-order result on any thread count.
///
/// Differences from the reference (spec 6.3): the error of an interior block is the mean over
/// its L-shaped overlap (the reference adds the two strip means, counting the corner twice);
/// the last valid offset is a candidate too; the output is cropped to `size`; random numbers
/// come from PCG32, not numpy's MT19937, so outputs are not byte-identical.
#include <tdf/core/image.h>

#include <cstdint>
#include <string>
#include <vector>

namespace tdf {

struct QuiltOptions {
    int size = 1024;          ///< output side in pixels (tileable: see quilt_output_side)
    int block = 40;           ///< block side in pixels (reference README example: 40)
    float overlap = 0.5f;     ///< overlap as a fraction of the block, in (0, 0.5]
    float tolerance = 0.1f;   ///< accept candidates with error < (1 + tolerance) * minimum
    std::uint64_t seed = 42;  ///< all random draws derive from it
    /// Candidates whose standard deviation is below this fraction of the median candidate's are
    /// never used, in [0, 1]. Plain Efros-Freeman (0, the reference) lets a low-contrast corner
    /// of an exemplar grow into large uniform areas, since flat blocks match flat overlaps best.
    float min_contrast = 0.0f;
    /// Blend across each boundary cut over +-feather pixels (0 = the reference's hard cut). A
    /// hard cut leaves a small step in a height map, which a normal map shows as a thin line.
    int feather = 0;
    /// With exemplar masks (see quilt): a candidate block is used only when at least this
    /// fraction of its pixels lies in its exemplar's mask, in [0, 1]. When fewer than 64
    /// candidates (or 2 % of all) reach it, the bar drops to the coverage of the 64th best, so
    /// a small textured region still quilts, from its most textured blocks.
    float min_coverage = 0.95f;
    /// Wrap-around: the last column and row also match (and are cut against) the first ones,
    /// so the output tiles the plane without seams.
    bool tileable = false;
};

struct QuiltStats {
    int blocks_per_side = 0;
    std::uint64_t candidates = 0;  ///< candidate positions evaluated, all blocks
    /// Mean per-pixel squared difference (channel mean) between the placed and the new content
    /// along the boundary cuts: what a viewer sees at the seams.
    double mean_cut_error = 0;
    /// Mean over blocks of the average overlap error of all candidates: the expected boundary
    /// error of random placement, for comparison with mean_cut_error.
    double mean_random_error = 0;
    /// The region coverage blocks needed: QuiltOptions::min_coverage, or less when too few
    /// blocks reach it (a region of thin rims or lines, which whole blocks cannot fill).
    double coverage_needed = 1;
};

struct QuiltResult {
    Image image;
    QuiltStats stats;
    /// 1 channel, the image's size: 1 on the pixels of the boundary cuts that remain visible
    /// (for seam measurements), else 0.
    Image seams;
};

/// The output side for `options`: `size` when not tileable; when tileable, the multiple of the
/// stride (block - overlap pixels) nearest to `size` (1020 for size 1024, block 40, overlap 0.5),
/// since a wrap-around grid needs a whole number of strides.
int quilt_output_side(const QuiltOptions& options);

/// Synthesises a texture from one or more exemplars (same channel count, each at least
/// block x block). `names` (optional, one per exemplar) label errors. `masks` (optional, one
/// per exemplar, 1 channel of its size, empty = all) mark where its texture lies: blocks are
/// drawn from there (QuiltOptions::min_coverage). Throws tdf::Error for invalid options,
/// exemplars smaller than the block, mismatched channels or sizes, or non-finite values.
QuiltResult quilt(const std::vector<Image>& exemplars, const QuiltOptions& options,
                  const std::vector<std::string>& names = {}, const std::vector<Image>& masks = {});

}  // namespace tdf
