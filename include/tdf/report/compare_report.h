#pragma once
/// The page of `tdf compare --html`: per file and per pass (EXR layer), image A, image B and a
/// heatmap of their difference side by side with the numbers; failing files first, and within
/// a file failing passes first.
#include <tdf/io/image_io.h>
#include <tdf/render/image_compare.h>

#include <string>
#include <vector>

namespace tdf {

struct ComparePass {
    std::string name;  ///< the layer ("albedo", ...; "image" for PNG/JPEG inputs)
    bool passed = true;
    std::size_t failed_pixels = 0;
    double fail_percent = 0;
    std::vector<ChannelStats> channels;  ///< this pass's channels
    std::string a_image, b_image;        ///< 8-bit previews (PNG paths)
    std::string heatmap;                 ///< max |a - b| over the channels, 0 black .. heat_scale bright
    double heat_scale = 0;               ///< the difference at the top of the colour ramp
};

struct CompareFile {
    std::string label;  ///< what the page calls it (file name, or path inside the folders)
    std::string a_path, b_path;
    /// "pass", "fail", "size_mismatch", "error" (unreadable, different channels), "missing_a",
    /// "missing_b".
    std::string result = "pass";
    std::string message;  ///< one line for results other than pass/fail
    int width = 0, height = 0;
    std::size_t compared_pixels = 0, failed_pixels = 0;
    double fail_percent = 0;
    ChannelStats overall;
    std::vector<ComparePass> passes;
};

struct CompareReport {
    std::string title = "tdf compare";
    CompareOptions thresholds;
    std::vector<CompareFile> files;
};

/// Compares `a` and `b` (already read, equal sizes; the caller reports size mismatches itself)
/// pass by pass, writes the previews and heatmaps as `<image_folder>/<prefix>_<pass>_{a,b,diff}.png`
/// and returns the file's entry. `overall` is the whole-file result of compare_layers with the
/// same options (its verdict is the file's).
CompareFile compare_file_entry(const std::string& label, const std::string& a_path, const std::string& b_path,
                               const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b,
                               const CompareResult& overall, const CompareOptions& options,
                               const std::string& image_folder, const std::string& prefix);

/// An entry without images for a file that could not be compared: `result` is one of
/// "size_mismatch", "error", "missing_a", "missing_b"; `message` is the one line shown.
CompareFile compare_file_problem(const std::string& label, const std::string& a_path,
                                 const std::string& b_path, const std::string& result,
                                 const std::string& message);

/// Writes the page to `html_path` (atomically), files ordered failures first (then by label).
void write_compare_report(const std::string& html_path, const CompareReport& report);

/// The folder beside a page for its images: `<dir>/<stem>_files`.
std::string report_files_folder(const std::string& html_path);

}  // namespace tdf
