#pragma once
/// Comparing two folders of renders (`tdf compare A B` with folders): files are paired by their
/// path relative to A and B, layers (render passes) by name, and every pair is compared with
/// compare_layers(). The result is a plain struct so that any report writer (terminal table,
/// JSON, an HTML page) can consume it.
#include <tdf/render/image_compare.h>

#include <string>
#include <vector>

namespace tdf {

struct FolderCompareOptions {
    CompareOptions compare;
    bool allow_missing = false;  ///< a file or layer of A absent from B is not a failure
    bool allow_extra = false;    ///< a file or layer of B absent from A is not a failure
    /// When not empty, |a - b| * diff_scale is written for every compared file that fails, as
    /// <diff_folder>/<relative path without extension>.diff.exr (A's layers).
    std::string diff_folder;
    float diff_scale = 16.f;
};

/// Extensions paired in folders (lower case): .exr, .png, .jpg, .jpeg. Other files are ignored.
bool is_comparable_image(const std::string& path);

struct FileComparison {
    enum class Status {
        Compared,      ///< read and compared (see result.passed)
        MissingInB,    ///< in A only
        ExtraInB,      ///< in B only
        SizeMismatch,  ///< different image sizes
        Error,         ///< unreadable file or different channels within a layer (see message)
    };
    std::string path;  ///< relative path, '/' separated
    Status status = Status::Compared;
    std::string message;  ///< for SizeMismatch and Error
    int a_width = 0, a_height = 0, b_width = 0, b_height = 0;
    CompareResult result;                     ///< the common layers, when Compared
    std::vector<std::string> missing_layers;  ///< layers of A absent from B
    std::vector<std::string> extra_layers;    ///< layers of B absent from A
    std::string diff_path;                    ///< written difference image, or empty
    bool passed = false;                      ///< after the allow_* options
};
const char* file_status_name(FileComparison::Status status);

struct FolderTotals {
    std::size_t files = 0;  ///< paired, missing and extra together
    std::size_t compared = 0;
    std::size_t passed = 0;
    std::size_t failed = 0;  ///< files that fail (missing/extra ones only without allow_*)
    std::size_t missing = 0, extra = 0, size_mismatch = 0, errors = 0;
    std::size_t rows = 0;  ///< (file, layer) rows compared
    std::size_t failed_rows = 0;
    ChannelStats overall;  ///< pooled over every compared value of every file
    double min_psnr = 0;   ///< worst row PSNR (+infinity when every row is identical)
};

struct FolderComparison {
    std::string a, b;
    FolderCompareOptions options;
    std::vector<FileComparison> files;  ///< sorted by path
    FolderTotals totals;
    bool passed = false;  ///< every file passed (and at least one pair existed or was allowed)
};

/// Compares every comparable image under `a` with the same relative path under `b` (recursive).
/// Throws tdf::Error when a folder does not exist or the options are invalid; per-file problems
/// are recorded in the result instead.
FolderComparison compare_folders(const std::string& a, const std::string& b,
                                 const FolderCompareOptions& options);

}  // namespace tdf
