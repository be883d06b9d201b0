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
    float fail = 1e-6f;        ///< per-channel difference above which a pixel fails (idiff default)
    float failpercent = 0.f;   ///< percent of compared pixels allowed to fail
    float hardfail = std::numeric_limits<float>::infinity();  ///< any difference above: fail
    /// Exclude pixels within this many pixels (square window) of a silhouette, i.e. where the
    /// hard coverage (mask > 0.5) changes in either image. Needs a `mask` layer in one image.
    int erode_mask = 0;
};

struct ChannelStats {
    std::string name;          ///< full channel name, e.g. "albedo.R"
    double mean_error = 0;     ///< mean |a - b| over compared pixels
    double rms_error = 0;
    double psnr = 0;           ///< 20 log10(1 / rms), infinity when equal
    double max_error = 0;
    int max_x = 0, max_y = 0;  ///< pixel of the max error (first one in row-major order)
};

struct CompareResult {
    int width = 0, height = 0;
    std::size_t compared_pixels = 0;  ///< after mask erosion
    std::size_t failed_pixels = 0;
    double fail_percent = 0;
    std::vector<ChannelStats> channels;
    ChannelStats overall;  ///< over every channel
    bool passed = false;
};

/// Compares two multi-layer images of equal size with the same channel names (any order).
/// Throws tdf::Error naming `a_name`/`b_name` when the sizes or channel sets differ (callers
/// check sizes first to report a size mismatch separately).
CompareResult compare_layers(const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b, const CompareOptions& options,
                             const std::string& a_name = "a", const std::string& b_name = "b");

/// |a - b| * scale per channel, in a's layer layout.
std::vector<ExrLayer> difference_layers(const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b, float scale);

}  // namespace tdf
