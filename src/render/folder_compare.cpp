#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/render/folder_compare.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>

namespace tdf {

namespace fs = std::filesystem;

namespace {

// Relative paths ('/' separated) of the comparable images under `root`, sorted.
std::set<std::string> list_images(const std::string& root) {
    std::set<std::string> out;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file()) continue;
        const std::string path = entry.path().string();
        if (is_comparable_image(path)) out.insert(fs::relative(entry.path(), root).generic_string());
    }
    return out;
}

void compare_file(const std::string& a_root, const std::string& b_root, const FolderCompareOptions& options,
                  FileComparison& f) {
    const std::string pa = (fs::path(a_root) / f.path).string(), pb = (fs::path(b_root) / f.path).string();
    std::vector<ExrLayer> la, lb;
    try {
        la = read_comparable_image(pa);
        lb = read_comparable_image(pb);
    } catch (const Error& e) {
        f.status = FileComparison::Status::Error;
        f.message = e.what();
        return;
    }
    if (la.empty() || lb.empty()) {
        f.status = FileComparison::Status::Error;
        f.message = la.empty() ? pa + ": no layers" : pb + ": no layers";
        return;
    }
    f.a_width = la.front().image.width(), f.a_height = la.front().image.height();
    f.b_width = lb.front().image.width(), f.b_height = lb.front().image.height();
    if (f.a_width != f.b_width || f.a_height != f.b_height) {
        f.status = FileComparison::Status::SizeMismatch;
        f.message = fmt::format("{}x{} vs {}x{}", f.a_width, f.a_height, f.b_width, f.b_height);
        return;
    }
    // Pair layers by name; keep the mask layers of both for --erode-mask even when one side lacks it.
    auto has = [](const std::vector<ExrLayer>& layers, const std::string& name) {
        return std::any_of(layers.begin(), layers.end(), [&](const ExrLayer& l) { return l.name == name; });
    };
    std::vector<ExrLayer> ca, cb;
    for (const ExrLayer& l : la) {
        if (has(lb, l.name))
            ca.push_back(l);
        else
            f.missing_layers.push_back(l.name);
    }
    for (const ExrLayer& l : lb) {
        if (has(la, l.name))
            cb.push_back(l);
        else
            f.extra_layers.push_back(l.name);
    }
    if (ca.empty()) {
        f.status = FileComparison::Status::Error;
        f.message = "no layer in common";
        return;
    }
    try {
        f.result = compare_layers(ca, cb, options.compare, pa, pb);
    } catch (const Error& e) {
        f.status = FileComparison::Status::Error;
        f.message = e.what();
        return;
    }
    f.status = FileComparison::Status::Compared;
    f.passed = f.result.passed && (options.allow_missing || f.missing_layers.empty()) &&
               (options.allow_extra || f.extra_layers.empty());
    if (!f.passed && !options.diff_folder.empty()) {
        const fs::path rel = fs::path(f.path);
        const fs::path out =
            fs::path(options.diff_folder) / rel.parent_path() / (rel.stem().string() + ".diff.exr");
        ensure_folder(out.parent_path().string());
        write_exr(out.string(), difference_layers(ca, cb, options.diff_scale));
        f.diff_path = out.string();
    }
}

}  // namespace

bool is_comparable_image(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == ".exr" || ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

const char* file_status_name(FileComparison::Status status) {
    switch (status) {
        case FileComparison::Status::Compared:
            return "compared";
        case FileComparison::Status::MissingInB:
            return "missing";
        case FileComparison::Status::ExtraInB:
            return "extra";
        case FileComparison::Status::SizeMismatch:
            return "size_mismatch";
        case FileComparison::Status::Error:
            return "error";
    }
    return "?";
}

FolderComparison compare_folders(const std::string& a, const std::string& b,
                                 const FolderCompareOptions& options) {
    validate_compare_options(options.compare);
    if (!(std::isfinite(options.diff_scale) && options.diff_scale > 0))
        throw_error("--diff-scale must be a finite number > 0, got {}", options.diff_scale);
    for (const std::string& folder : {a, b})
        if (!fs::is_directory(folder)) throw_error("{}: not a folder", folder);
    FolderComparison r;
    r.a = a;
    r.b = b;
    r.options = options;
    const std::set<std::string> in_a = list_images(a), in_b = list_images(b);
    std::set<std::string> all = in_a;
    all.insert(in_b.begin(), in_b.end());
    for (const std::string& path : all) {
        FileComparison f;
        f.path = path;
        if (!in_b.count(path)) {
            f.status = FileComparison::Status::MissingInB;
            f.passed = options.allow_missing;
        } else if (!in_a.count(path)) {
            f.status = FileComparison::Status::ExtraInB;
            f.passed = options.allow_extra;
        } else {
            compare_file(a, b, options, f);
        }
        r.files.push_back(std::move(f));
    }

    FolderTotals& t = r.totals;
    t.overall.name = "all";
    t.min_psnr = std::numeric_limits<double>::infinity();
    double sum = 0, sum_sq = 0;
    for (const FileComparison& f : r.files) {
        ++t.files;
        t.passed += f.passed;
        t.failed += !f.passed;
        switch (f.status) {
            case FileComparison::Status::MissingInB:
                ++t.missing;
                break;
            case FileComparison::Status::ExtraInB:
                ++t.extra;
                break;
            case FileComparison::Status::SizeMismatch:
                ++t.size_mismatch;
                break;
            case FileComparison::Status::Error:
                ++t.errors;
                break;
            case FileComparison::Status::Compared: {
                ++t.compared;
                const ChannelStats& o = f.result.overall;
                sum += o.mean_error * double(o.count);
                sum_sq += o.rms_error * o.rms_error * double(o.count);
                t.overall.count += o.count;
                t.overall.nonfinite += o.nonfinite;
                if (o.max_error > t.overall.max_error) {
                    t.overall.max_error = o.max_error;
                    t.overall.max_x = o.max_x;
                    t.overall.max_y = o.max_y;
                }
                for (const LayerResult& l : f.result.layers) {
                    ++t.rows;
                    t.failed_rows += !l.passed;
                    t.min_psnr = std::min(t.min_psnr, l.stats.psnr);
                }
                break;
            }
        }
    }
    t.overall.mean_error = t.overall.count ? sum / double(t.overall.count) : 0.0;
    t.overall.rms_error = t.overall.count ? std::sqrt(sum_sq / double(t.overall.count)) : 0.0;
    t.overall.psnr = t.overall.rms_error > 0 ? 20.0 * std::log10(1.0 / t.overall.rms_error)
                                             : std::numeric_limits<double>::infinity();
    // Two empty folders prove nothing: no files is a failure.
    r.passed = t.files > 0 && t.failed == 0;
    return r;
}

}  // namespace tdf
