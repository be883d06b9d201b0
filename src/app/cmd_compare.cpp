// `tdf compare A B`: idiff-style comparison of two images, or of two folders of images paired by
// relative path and layer (docs/commands/compare.md).
// Exit codes: 0 pass; 1 fail (also unreadable files, different channel sets, bad options); 2 size
// mismatch of two single images. Folders: 0 when every file passes, else 1.
#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/render/folder_compare.h>
#include <tdf/render/image_compare.h>
#include <tdf/report/compare_report.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "commands.h"

namespace tdf::app {

namespace {

struct CompareCliOptions {
    std::string a, b;
    CompareOptions compare;
    std::string diff;
    float diff_scale = 16.f;
    std::string html;
    bool json = false;
    bool allow_missing = false;
    bool allow_extra = false;
};

constexpr int kExitPass = 0;
constexpr int kExitFail = 1;
constexpr int kExitSizeMismatch = 2;

// JSON has no infinity: a number, or null for +infinity (PSNR of equal values, no hardfail).
Json number_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json stats_json(const ChannelStats& s) {
    return {{"name", s.name},
            {"mean_error", s.mean_error},
            {"rms_error", s.rms_error},
            {"psnr", number_or_null(s.psnr)},
            {"psnr_infinite", std::isinf(s.psnr)},
            {"max_error", s.max_error},
            {"max_pixel", {s.max_x, s.max_y}},
            {"compared_values", s.count},
            {"nonfinite_values", s.nonfinite},
            {"first_nonfinite_pixel", s.nonfinite ? Json{s.nonfinite_x, s.nonfinite_y} : Json(nullptr)}};
}

Json layer_json(const LayerResult& l) {
    Json j = stats_json(l.stats);
    j["layer"] = l.name;
    j["failed_pixels"] = l.failed_pixels;
    j["fail_percent"] = l.fail_percent;
    j["result"] = l.passed ? "pass" : "fail";
    return j;
}

Json thresholds_json(const CompareCliOptions& o) {
    return {{"fail", o.compare.fail},
            {"failpercent", o.compare.failpercent},
            {"hardfail", number_or_null(o.compare.hardfail)},
            {"erode_mask", o.compare.erode_mask},
            {"allow_nonfinite", o.compare.allow_nonfinite},
            {"allow_missing", o.allow_missing},
            {"allow_extra", o.allow_extra}};
}

std::string psnr_text(double psnr) { return std::isinf(psnr) ? "inf" : fmt::format("{:.2f}", psnr); }

int run_compare_files(const CompareCliOptions& o) {
    if (!o.diff.empty()) check_output_extension(o.diff, {".exr"}, "--diff (a multi-layer float image)");
    const std::vector<ExrLayer> a = read_comparable_image(o.a);
    const std::vector<ExrLayer> b = read_comparable_image(o.b);
    if (a.empty()) throw_error("{}: no layers", o.a);
    if (b.empty()) throw_error("{}: no layers", o.b);
    const Image& ia = a.front().image;
    const Image& ib = b.front().image;
    if (ia.width() != ib.width() || ia.height() != ib.height()) {
        if (o.json)
            std::printf("%s\n",
                        Json({{"result", "size_mismatch"},
                              {"a", o.a},
                              {"b", o.b},
                              {"a_size", {ia.width(), ia.height()}},
                              {"b_size", {ib.width(), ib.height()}}})
                            .dump(2)
                            .c_str());
        std::fprintf(stderr,
                     "tdf compare: %s is %dx%d but %s is %dx%d\n",
                     o.a.c_str(),
                     ia.width(),
                     ia.height(),
                     o.b.c_str(),
                     ib.width(),
                     ib.height());
        if (!o.html.empty())
            write_compare_report(o.html, {"tdf compare", o.compare,
                                          {compare_file_problem(o.a + " vs " + o.b, o.a, o.b, "size_mismatch",
                                                                fmt::format("A is {}x{} but B is {}x{}", ia.width(),
                                                                            ia.height(), ib.width(), ib.height()))}});
        return kExitSizeMismatch;
    }
    const CompareResult r = compare_layers(a, b, o.compare, o.a, o.b);
    if (!o.diff.empty()) write_exr(o.diff, difference_layers(a, b, o.diff_scale));
    if (!o.html.empty())
        write_compare_report(o.html, {"tdf compare", o.compare,
                                      {compare_file_entry(std::filesystem::path(o.a).filename().string() + " vs " +
                                                              std::filesystem::path(o.b).filename().string(),
                                                          o.a, o.b, a, b, r, o.compare,
                                                          report_files_folder(o.html), "file")}});
    if (o.json) {
        Json channels = Json::array(), layers = Json::array();
        for (const auto& s : r.channels) channels.push_back(stats_json(s));
        for (const auto& l : r.layers) layers.push_back(layer_json(l));
        Json report = {{"result", r.passed ? "pass" : "fail"},
                       {"a", o.a},
                       {"b", o.b},
                       {"size", {r.width, r.height}},
                       {"compared_pixels", r.compared_pixels},
                       {"failed_pixels", r.failed_pixels},
                       {"fail_percent", r.fail_percent},
                       {"thresholds", thresholds_json(o)},
                       {"overall", stats_json(r.overall)},
                       {"layers", layers},
                       {"channels", channels}};
        std::printf("%s\n", report.dump(2).c_str());
    } else {
        std::printf("Comparing \"%s\" and \"%s\" (%dx%d, %zu pixels compared)\n",
                    o.a.c_str(),
                    o.b.c_str(),
                    r.width,
                    r.height,
                    r.compared_pixels);
        std::printf("  %-32s %12s %12s %9s %12s  %-12s %s\n",
                    "channel",
                    "mean error",
                    "RMS",
                    "PSNR",
                    "max error",
                    "at",
                    "non-finite");
        auto row = [](const ChannelStats& s) {
            std::printf("  %-32s %12.6g %12.6g %9s %12.6g  %-12s %zu\n",
                        s.name.c_str(),
                        s.mean_error,
                        s.rms_error,
                        psnr_text(s.psnr).c_str(),
                        s.max_error,
                        fmt::format("({}, {})", s.max_x, s.max_y).c_str(),
                        s.nonfinite);
        };
        for (const auto& s : r.channels) row(s);
        row(r.overall);
        std::printf("  %zu pixels (%.4g%%) over %g\n%s\n",
                    r.failed_pixels,
                    r.fail_percent,
                    double(o.compare.fail),
                    r.passed ? "PASS" : "FAILURE");
    }
    return r.passed ? kExitPass : kExitFail;
}

// The --html page of a folder comparison: compared files are read again for their previews
// (the comparison keeps numbers, not pixels); the others get a one-line entry.
void write_folder_page(const CompareCliOptions& o, const FolderComparison& r) {
    CompareReport report{"tdf compare " + r.a + " " + r.b, o.compare, {}};
    const std::string images = report_files_folder(o.html);
    int index = 0;
    for (const FileComparison& f : r.files) {
        const std::string a = (std::filesystem::path(r.a) / f.path).string();
        const std::string b = (std::filesystem::path(r.b) / f.path).string();
        switch (f.status) {
            case FileComparison::Status::Compared:
                report.files.push_back(compare_file_entry(f.path, a, b, read_comparable_image(a),
                                                          read_comparable_image(b), f.result, o.compare, images,
                                                          fmt::format("file{:04d}", index++)));
                break;
            case FileComparison::Status::MissingInB:
                report.files.push_back(compare_file_problem(f.path, a, b, "missing_b", "only in " + r.a));
                break;
            case FileComparison::Status::ExtraInB:
                report.files.push_back(compare_file_problem(f.path, a, b, "missing_a", "only in " + r.b));
                break;
            case FileComparison::Status::SizeMismatch:
                report.files.push_back(compare_file_problem(f.path, a, b, "size_mismatch", f.message));
                break;
            case FileComparison::Status::Error:
                report.files.push_back(compare_file_problem(f.path, a, b, "error", f.message));
                break;
        }
    }
    write_compare_report(o.html, report);
}

// `tdf compare --json` on two folders: every file's result and the totals.
void print_folder_json(const CompareCliOptions& o, const FolderComparison& r) {
    const FolderTotals& t = r.totals;
    Json files = Json::array();
    for (const FileComparison& f : r.files) {
        Json j = {{"path", f.path},
                  {"status", file_status_name(f.status)},
                  {"result", f.passed ? "pass" : "fail"}};
        if (!f.message.empty()) j["message"] = f.message;
        if (f.status == FileComparison::Status::Compared) {
            Json layers = Json::array();
            for (const LayerResult& l : f.result.layers) layers.push_back(layer_json(l));
            j["size"] = {f.result.width, f.result.height};
            j["compared_pixels"] = f.result.compared_pixels;
            j["failed_pixels"] = f.result.failed_pixels;
            j["fail_percent"] = f.result.fail_percent;
            j["overall"] = stats_json(f.result.overall);
            j["layers"] = layers;
            j["missing_layers"] = f.missing_layers;
            j["extra_layers"] = f.extra_layers;
        }
        if (!f.diff_path.empty()) j["diff"] = f.diff_path;
        files.push_back(j);
    }
    Json totals = {{"files", t.files},
                   {"compared", t.compared},
                   {"passed", t.passed},
                   {"failed", t.failed},
                   {"missing", t.missing},
                   {"extra", t.extra},
                   {"size_mismatch", t.size_mismatch},
                   {"errors", t.errors},
                   {"rows", t.rows},
                   {"failed_rows", t.failed_rows},
                   {"min_psnr", number_or_null(t.min_psnr)},
                   {"overall", stats_json(t.overall)}};
    Json report = {{"result", r.passed ? "pass" : "fail"},
                   {"a", r.a},
                   {"b", r.b},
                   {"thresholds", thresholds_json(o)},
                   {"files", files},
                   {"totals", totals}};
    std::printf("%s\n", report.dump(2).c_str());
}

// The folder comparison as a table: a row per file and layer, then the totals.
void print_folder_table(const CompareCliOptions& o, const FolderComparison& r) {
    const FolderTotals& t = r.totals;
    std::printf("Comparing folders \"%s\" and \"%s\"\n", r.a.c_str(), r.b.c_str());
    std::printf("  %-36s %-26s %9s %12s %-12s %9s  %s\n",
                "file",
                "pass",
                "PSNR",
                "max error",
                "at",
                "% over",
                "result");
    for (const FileComparison& f : r.files) {
        if (f.status != FileComparison::Status::Compared) {
            std::printf("  %-36s %-26s %9s %12s %-12s %9s  %s%s%s\n",
                        f.path.c_str(),
                        "-",
                        "-",
                        "-",
                        "-",
                        "-",
                        f.passed ? "ok: " : "FAIL: ",
                        file_status_name(f.status),
                        f.message.empty() ? "" : (" (" + f.message + ")").c_str());
            continue;
        }
        for (const LayerResult& l : f.result.layers) {
            std::string at = fmt::format("({}, {})", l.stats.max_x, l.stats.max_y);
            std::string verdict = l.passed ? "pass" : "FAIL";
            if (l.stats.nonfinite) verdict += fmt::format(" ({} non-finite)", l.stats.nonfinite);
            std::printf("  %-36s %-26s %9s %12.6g %-12s %8.4g%%  %s\n",
                        f.path.c_str(),
                        l.name.empty() ? "(image)" : l.name.c_str(),
                        psnr_text(l.stats.psnr).c_str(),
                        l.stats.max_error,
                        at.c_str(),
                        l.fail_percent,
                        verdict.c_str());
        }
        for (const auto& name : f.missing_layers)
            std::printf("  %-36s %-26s %s\n",
                        f.path.c_str(),
                        name.c_str(),
                        o.allow_missing ? "ok: missing in B" : "FAIL: missing in B");
        for (const auto& name : f.extra_layers)
            std::printf("  %-36s %-26s %s\n",
                        f.path.c_str(),
                        name.c_str(),
                        o.allow_extra ? "ok: extra in B" : "FAIL: extra in B");
        if (!f.diff_path.empty())
            std::printf("  %-36s diff written to %s\n", f.path.c_str(), f.diff_path.c_str());
    }
    std::printf(
        "  %zu files: %zu compared, %zu passed, %zu failed (%zu missing, %zu extra, %zu size mismatches, "
        "%zu errors); %zu of %zu rows failed; overall PSNR %s, max error %.6g, worst row PSNR %s\n%s\n",
        t.files,
        t.compared,
        t.passed,
        t.failed,
        t.missing,
        t.extra,
        t.size_mismatch,
        t.errors,
        t.failed_rows,
        t.rows,
        psnr_text(t.overall.psnr).c_str(),
        t.overall.max_error,
        psnr_text(t.min_psnr).c_str(),
        r.passed ? "PASS" : "FAILURE");
}

int run_compare_folders(const CompareCliOptions& o) {
    FolderCompareOptions fo;
    fo.compare = o.compare;
    fo.allow_missing = o.allow_missing;
    fo.allow_extra = o.allow_extra;
    fo.diff_folder = o.diff;
    fo.diff_scale = o.diff_scale;
    const FolderComparison r = compare_folders(o.a, o.b, fo);
    if (!o.html.empty()) write_folder_page(o, r);
    if (o.json)
        print_folder_json(o, r);
    else
        print_folder_table(o, r);
    return r.passed ? kExitPass : kExitFail;
}

int run_compare(const CompareCliOptions& o) {
    validate_compare_options(o.compare);
    if (!(std::isfinite(o.diff_scale) && o.diff_scale > 0))
        throw_error("--diff-scale must be a finite number > 0, got {}", o.diff_scale);
    const bool da = std::filesystem::is_directory(o.a), db = std::filesystem::is_directory(o.b);
    if (da != db) throw_error("{} and {} must both be folders or both be images", o.a, o.b);
    if (da) return run_compare_folders(o);
    if (o.allow_missing || o.allow_extra)
        throw_error("--allow-missing and --allow-extra apply to folders only");
    return run_compare_files(o);
}

}  // namespace

Command register_compare(CLI::App& root) {
    auto o = std::make_shared<CompareCliOptions>();
    Command command;
    CLI::App* app =
        root.add_subcommand("compare",
                            "compare two images channel by channel like idiff, or two folders file by file "
                            "and layer by layer (exit 0 "
                            "pass, 1 fail / unreadable / bad option, 2 size mismatch of two images)");
    app->add_option("a", o->a, "first image (EXR, PNG or JPEG) or folder")->required();
    app->add_option("b", o->b, "second image (same size and channel names) or folder")->required();
    app->add_option(
           "--fail", o->compare.fail, "a pixel fails when a channel differs by more than this (finite, >= 0)")
        ->capture_default_str();
    app->add_option("--failpercent", o->compare.failpercent, "percent of pixels allowed to fail, in [0, 100]")
        ->capture_default_str();
    app->add_option(
           "--hardfail", o->compare.hardfail, "fail when any difference exceeds this (>= 0, inf = none)")
        ->capture_default_str();
    app->add_option("--erode-mask",
                    o->compare.erode_mask,
                    "ignore pixels within N pixels of a silhouette (needs a mask layer)")
        ->capture_default_str();
    app->add_flag("--allow-nonfinite",
                  o->compare.allow_nonfinite,
                  "NaN vs NaN and equal infinities count as equal (otherwise any non-finite value fails)")
        ->capture_default_str();
    app->add_flag(
           "--allow-missing", o->allow_missing, "folders: files or layers of A absent from B do not fail")
        ->capture_default_str();
    app->add_flag("--allow-extra", o->allow_extra, "folders: files or layers of B absent from A do not fail")
        ->capture_default_str();
    app->add_option(
        "--diff",
        o->diff,
        "images: write |a - b| * --diff-scale to this EXR; folders: write <path>.diff.exr under this "
        "folder for every failing file");
    app->add_option("--diff-scale", o->diff_scale, "scale of the difference image (finite, > 0)")
        ->capture_default_str();
    app->add_option("--html", o->html,
                    "write an HTML page with A, B and a difference heatmap per pass (images in <page>_files/)");
    app->add_flag("--json", o->json, "print the report as JSON on stdout")->capture_default_str();
    command.app = app;
    command.run = [o] { return run_compare(*o); };
    return command;
}

}  // namespace tdf::app
