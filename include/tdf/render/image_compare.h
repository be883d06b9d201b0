#pragma once
/// Comparing two renders channel by channel with OpenImageIO idiff's semantics: a pixel
/// "fails" when any of its channels differs by more than `fail`; the comparison fails when
/// more than `failpercent` percent of the compared pixels fail, or when any difference exceeds
/// `hardfail`. Used by `tdf compare` and the golden-image tests.
#include <tdf/io/image_io.h>

#include <limits>
#include <string>
#include <vector>

namespace tdf {

struct CompareOptions {
    float fail = 1e-6f;       ///< per-channel difference above which a pixel fails (idiff default)
    float failpercent = 0.f;  ///< percent of compared pixels allowed to fail
    float hardfail = std::numeric_limits<float>::infinity();  ///< any difference above: fail
    /// Exclude pixels within this many pixels (square window) of a silhouette, i.e. where the
    /// hard coverage (mask > 0.5) changes in either image. Needs a `mask` layer in one image.
    int erode_mask = 0;
    /// NaN or infinite values fail the comparison (and count as failed pixels) unless this is
    /// set; with it, NaN against NaN and an infinity against the same infinity count as equal
    /// (anything else against a non-finite value still fails).
    bool allow_nonfinite = false;
};

/// Throws tdf::Error naming the option when a value is out of range: fail, failpercent and
/// erode_mask must be finite and >= 0, failpercent <= 100, hardfail >= 0 (+infinity allowed,
/// NaN never).
void validate_compare_options(const CompareOptions& options);

/// Error statistics over the compared values of one channel, one layer or everything. Only
/// finite differences enter mean, RMS, PSNR and max, so these are always finite numbers (0 when
/// nothing was compared); values where either image is non-finite are counted in `nonfinite`.
struct ChannelStats {
    std::string name;       ///< full channel name ("albedo.R"), layer name, or "all"
    double mean_error = 0;  ///< mean |a - b|
    double rms_error = 0;
    double psnr = 0;  ///< 20 log10(1 / rms); +infinity exactly when rms == 0
    double max_error = 0;
    int max_x = 0, max_y = 0;   ///< pixel of the max error (first one in row-major order)
    std::size_t count = 0;      ///< compared values with a finite difference
    std::size_t nonfinite = 0;  ///< values where a or b is NaN/Inf and they do not count as equal
    int nonfinite_x = -1, nonfinite_y = -1;  ///< first such pixel, or -1
};

/// One layer (render pass) of a comparison: its channels pooled, and its own pass/fail.
struct LayerResult {
    std::string name;  ///< layer name ("albedo"), "" for the unnamed layer of a PNG
    ChannelStats stats;
    std::size_t failed_pixels = 0;  ///< pixels where a channel of this layer fails
    double fail_percent = 0;
    bool passed = false;
};

struct CompareResult {
    int width = 0, height = 0;
    std::size_t compared_pixels = 0;  ///< after mask erosion
    std::size_t failed_pixels = 0;    ///< over every channel
    double fail_percent = 0;
    std::vector<ChannelStats> channels;  ///< sorted by name
    std::vector<LayerResult> layers;     ///< in a's layer order
    ChannelStats overall;                ///< over every channel
    bool passed = false;  ///< fail_percent <= failpercent, max <= hardfail, no non-finite failure
};

/// Compares two multi-layer images of equal size with the same channel names (any order).
/// Throws tdf::Error naming `a_name`/`b_name` when the sizes or channel sets differ (callers
/// check sizes first to report a size mismatch separately).
CompareResult compare_layers(const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b,
                             const CompareOptions& options, const std::string& a_name = "a",
                             const std::string& b_name = "b");

/// Reads an image for comparison: an EXR's layers, or a PNG/JPEG as one unnamed layer with
/// channels Y, YA, RGB or RGBA.
std::vector<ExrLayer> read_comparable_image(const std::string& path);

/// |a - b| * scale per channel, in a's layer layout (a non-finite difference is written as is).
std::vector<ExrLayer> difference_layers(const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b,
                                        float scale);

}  // namespace tdf
