#pragma once
/// Does a tactile normal map keep the material it came from? Statistics of the *detail* of a
/// normal map (its slopes after a high-pass, so the curvature of a pressed object does not
/// count), the textured region of a sample, and a texture-similarity distance. `tdf tactile
/// convert` reports them for its input region and its output (docs/commands/tactile.md).
///
/// The measure is the one of the project's yardstick script (check_tactile_material.py), so
/// both give the same numbers: slopes sx = nx / nz, sy = ny / nz (nz clamped to at least 1e-3)
/// minus their Gaussian low-pass (sigma 12 px, mirrored reflect-101 borders, taps out to
/// int(3 sigma + 1)); detail tilt = atan(|(sx, sy)|) in degrees.
#include <tdf/core/config.h>
#include <tdf/core/image.h>

#include <string>
#include <vector>

namespace tdf {

/// Gaussian sigma of the detail high-pass, pixels (the yardstick's).
constexpr float kDetailSigmaPx = 12.0f;
/// Texels tilted less than this are "flat", degrees.
constexpr double kFlatDegrees = 1.0;

/// High-passed slopes of decoded normals (3+ channels; the length does not matter).
struct DetailSlopes {
    Image slopes;  ///< 2 channels: detail sx (right), sy (up), dimensionless
    Image tilt;    ///< 1 channel: atan(|slope|) in degrees
};
DetailSlopes detail_slopes(const Image& normals, float sigma_px = kDetailSigmaPx);

/// Separable Gaussian blur of every channel, mirrored (reflect-101) borders, taps out to
/// int(3 sigma + 1) pixels, weights normalised; the yardstick's `gblur`.
Image gaussian_blur_mirrored(const Image& image, float sigma_px);

/// The textured region of a sample from its detail tilt (1 channel, degrees): texels whose
/// 15 x 15 local mean tilt (edge-replicated borders) is at least half the 90th percentile
/// (linear interpolation) of that local mean. Drops the flat gel around a contact and the
/// flat margins of a height image. Returns a 1-channel 0/1 mask.
Image texture_region(const Image& tilt_degrees);

/// Fraction of the mask's texels that are 1 (mask 1 channel; empty = all).
double mask_fraction(const Image& mask);

/// What a texture-similarity distance compares (see texture_distance).
struct MaterialStatistics {
    double fraction = 1;       ///< share of the image's texels counted (the region's area)
    double mean_tilt = 0;      ///< mean detail tilt, degrees
    double flat_fraction = 0;  ///< share of counted texels with detail tilt < 1 degree
    /// Detail tilt histogram: 16 bins over [0, tilt_range] degrees, the last bin takes the rest.
    std::vector<double> tilt_histogram;
    /// Gradient orientation histogram (HOG-like): 8 bins over the direction of the detail
    /// slope modulo 180 degrees, weighted by |slope|, normalised to sum 1. Tells ridges and
    /// grooves from isotropic bumps, and a blocky grid from round cells.
    std::vector<double> orientation_histogram;
    /// Filter response per scale: share of the detail slope energy in the octave bands
    /// [1, 2), [2, 4), [4, 8) px Gaussian differences, below 1 px and above 8 px (5 numbers,
    /// sum 1). Tells fine pores from coarse cells at the same mean tilt.
    std::vector<double> scale_energy;
};

/// Statistics of the texels of `detail` where `mask` (1 channel, empty = all) is non-zero;
/// the tilt histogram spans [0, tilt_range] degrees (pass the same range for maps that are
/// to be compared).
MaterialStatistics material_statistics(const DetailSlopes& detail, const Image& mask, double tilt_range);

/// Texture-similarity distance in [0, 1]: the mean of the L1 distances (each in [0, 2]) of
/// the tilt, orientation and scale histograms, halved. 0 = the same statistics.
double texture_distance(const MaterialStatistics& a, const MaterialStatistics& b);

/// Input region against output, as `tdf tactile convert` reports it.
struct MaterialComparison {
    MaterialStatistics region;  ///< the input's textured region
    MaterialStatistics output;  ///< the whole output
    double tilt_ratio = 0;      ///< output mean tilt / region mean tilt
    double flat_excess = 0;     ///< output flat fraction - region flat fraction
    double distance = 0;        ///< texture_distance(region, output)
    /// Its three L1 terms (each in [0, 2]): tilt, orientation and scale histograms.
    double tilt_l1 = 0, orientation_l1 = 0, scale_l1 = 0;
    /// The whole input against its own region: what an output that copies the input's whole
    /// layout (flat gel, or smooth parts of the material the region leaves out) would measure.
    double input_mean_tilt = 0, input_flat = 0, input_tilt_ratio = 0;
    /// The numbers as JSON (keys as the yardstick's, plus the distance and its terms and the whole
    /// input's numbers), rounded to 4 decimals (the L1 terms to 3).
    Json to_json() const;
    /// to_json() on one line.
    std::string json() const;
};

/// `value` rounded to `digits` significant digits (what a report states of a measured number).
double rounded_significant(double value, int digits);

/// Compares `output` normals with the textured region of `input` normals (both decoded, 3+
/// channels). `region` (1 channel, the input's size) selects the input texels; empty = found
/// with texture_region. The tilt histograms span [0, 3 x region mean tilt].
MaterialComparison compare_material(const Image& input, const Image& region, const Image& output);

/// Limits a converted map should stay within (issue 11); `check` lists what is outside.
struct MaterialLimits {
    double min_ratio = 0.85, max_ratio = 1.15;  ///< output / region mean detail tilt
    double flat_slack = 0.05;                   ///< output flat fraction - region's
    double max_distance = 0.25;                 ///< texture_distance
};
std::vector<std::string> check_material(const MaterialComparison& c, const MaterialLimits& limits = {});

/// How far comparisons lie outside `limits`, summed over inputs: relative excess of the tilt
/// ratio beyond its bounds + flat excess beyond the slack + distance beyond its bound. 0 when
/// all are within (`tdf tactile convert --synthesis auto` keeps the synthesis that misses less).
double material_misses(const std::vector<MaterialComparison>& comparisons, const MaterialLimits& limits = {});

/// Are the seams of a synthesised height map invisible (issue 11, goal 5)? Measured on the
/// heights with periodic forward differences (the map tiles).
struct SeamStatistics {
    /// Mean squared height gradient on the pixels of the boundary cuts (QuiltResult::seams,
    /// where the cuts were even after a refinement moved them) / the same on all other pixels.
    double cut_ratio = 0;
    /// Mean |height step| across the wrap-around (last -> first column, last -> first row) /
    /// the mean step between the kWrapBaselineLines neighbouring lines on either side of it
    /// (same forward difference; those lines cross the same content as the wrap).
    double wrap_ratio_columns = 0, wrap_ratio_rows = 0;
    /// First and second (last and second-to-last) rows or columns are identical.
    bool duplicated_border = false;
    std::string json() const;
};
/// Seams count as invisible up to this ratio to the interior (issue 11, goal 5).
constexpr double kSeamLimit = 1.2;
/// Lines on either side of the wrap-around that its step is compared with. The nearest lines:
/// a seam is a one-line step, and farther lines cross other content (on the shared samples,
/// 0-8 % of ordinary lines step more than 1.2x their 2 + 2 neighbours, 0-19 % their 4 + 4).
constexpr int kWrapBaselineLines = 2;
/// `seams`: 1 channel, the map's size, non-zero on cut pixels (empty: cut_ratio stays 0). The
/// wrap's steps sum over the channels of `height` (the cut ratio uses channel 0).
SeamStatistics seam_statistics(const Image& height, const Image& seams);

/// How visible the repeats of a tangent-space normal map (3 channels, unit normals) are when it
/// is tiled: seam_statistics of its two slopes (n_x / n_z and n_y / n_z) together; cut_ratio 0.
SeamStatistics normal_map_wrap_statistics(const Image& normals);

/// Decoded normals as a file of `bits` (8 or 16) would give them back: the reference's
/// floor((n * 0.5 + 0.5) * (2^bits - 1)) encoding, then decoded. What a reader of the written
/// PNG sees (a 0.5 degree relief does not survive 8 bits).
Image quantized_normals(const Image& normals, int bits);

}  // namespace tdf
