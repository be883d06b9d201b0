// `tdf compare a.exr b.exr`: idiff-style image comparison (README "tdf compare").
// Exit codes: 0 pass, 1 fail (or a file / channel error), 2 size mismatch.
#include "commands.h"

#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/render/image_compare.h>

#include <cmath>
#include <cstdio>

namespace tdf::app {

namespace {

struct CompareCliOptions {
    std::string a, b;
    CompareOptions compare;
    std::string diff;
    float diff_scale = 16.f;
    bool json = false;
};

constexpr int kExitPass = 0;
constexpr int kExitFail = 1;
constexpr int kExitSizeMismatch = 2;

std::vector<ExrLayer> read_layers(const std::string& path) {
    if (lower_extension(path) == ".exr") return read_exr_layers(path);
    // PNG / JPEG: one unnamed layer with R, G, B, A names by channel count.
    Image image = read_image(path);
    static const std::vector<std::vector<std::string>> names = {{"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
    return {{"", names[std::size_t(image.channels() - 1)], std::move(image)}};
}

Json stats_json(const ChannelStats& s) {
    return {{"channel", s.name},
            {"mean_error", s.mean_error},
            {"rms_error", s.rms_error},
            {"psnr", std::isinf(s.psnr) ? Json("inf") : Json(s.psnr)},
            {"max_error", std::isinf(s.max_error) ? Json("inf") : Json(s.max_error)},
            {"max_pixel", {s.max_x, s.max_y}}};
}

int run_compare(const CompareCliOptions& o) {
    if (!o.diff.empty()) check_output_extension(o.diff, {".exr"}, "--diff (a multi-layer float image)");
    const std::vector<ExrLayer> a = read_layers(o.a);
    const std::vector<ExrLayer> b = read_layers(o.b);
    const Image& ia = a.front().image;
    const Image& ib = b.front().image;
    if (ia.width() != ib.width() || ia.height() != ib.height()) {
        if (o.json)
            std::printf("%s\n", Json({{"result", "size_mismatch"},
                                      {"a_size", {ia.width(), ia.height()}},
                                      {"b_size", {ib.width(), ib.height()}}})
                                    .dump(2)
                                    .c_str());
        std::fprintf(stderr, "tdf compare: %s is %dx%d but %s is %dx%d\n", o.a.c_str(), ia.width(), ia.height(),
                     o.b.c_str(), ib.width(), ib.height());
        return kExitSizeMismatch;
    }
    const CompareResult r = compare_layers(a, b, o.compare, o.a, o.b);
    if (!o.diff.empty()) write_exr(o.diff, difference_layers(a, b, o.diff_scale));
    if (o.json) {
        Json channels = Json::array();
        for (const auto& s : r.channels) channels.push_back(stats_json(s));
        Json report = {{"result", r.passed ? "pass" : "fail"},
                       {"a", o.a},
                       {"b", o.b},
                       {"size", {r.width, r.height}},
                       {"compared_pixels", r.compared_pixels},
                       {"failed_pixels", r.failed_pixels},
                       {"fail_percent", r.fail_percent},
                       {"thresholds",
                        {{"fail", o.compare.fail},
                         {"failpercent", o.compare.failpercent},
                         {"hardfail", std::isinf(o.compare.hardfail) ? Json("inf") : Json(o.compare.hardfail)},
                         {"erode_mask", o.compare.erode_mask}}},
                       {"overall", stats_json(r.overall)},
                       {"channels", channels}};
        std::printf("%s\n", report.dump(2).c_str());
    } else {
        std::printf("Comparing \"%s\" and \"%s\" (%dx%d, %zu pixels compared)\n", o.a.c_str(), o.b.c_str(), r.width,
                    r.height, r.compared_pixels);
        std::printf("  %-32s %12s %12s %9s %12s  %s\n", "channel", "mean error", "RMS", "PSNR", "max error", "at");
        for (const auto& s : r.channels)
            std::printf("  %-32s %12.6g %12.6g %9.2f %12.6g  (%d, %d)\n", s.name.c_str(), s.mean_error, s.rms_error,
                        s.psnr, s.max_error, s.max_x, s.max_y);
        std::printf("  %-32s %12.6g %12.6g %9.2f %12.6g  (%d, %d)\n", "all", r.overall.mean_error, r.overall.rms_error,
                    r.overall.psnr, r.overall.max_error, r.overall.max_x, r.overall.max_y);
        std::printf("  %zu pixels (%.4g%%) over %g\n%s\n", r.failed_pixels, r.fail_percent, double(o.compare.fail),
                    r.passed ? "PASS" : "FAILURE");
    }
    return r.passed ? kExitPass : kExitFail;
}

}  // namespace

Command register_compare(CLI::App& root) {
    auto o = std::make_shared<CompareCliOptions>();
    Command command;
    CLI::App* app = root.add_subcommand(
        "compare",
        "compare two images channel by channel like idiff (exit 0 pass, 1 fail or unreadable file, 2 size mismatch)");
    app->add_option("a", o->a, "first image (EXR, PNG or JPEG)")->required();
    app->add_option("b", o->b, "second image (same size and channel names)")->required();
    app->add_option("--fail", o->compare.fail, "a pixel fails when a channel differs by more than this")
        ->capture_default_str();
    app->add_option("--failpercent", o->compare.failpercent, "percent of pixels allowed to fail")
        ->check(CLI::Range(0.f, 100.f))
        ->capture_default_str();
    app->add_option("--hardfail", o->compare.hardfail, "fail when any difference exceeds this")->capture_default_str();
    app->add_option("--erode-mask", o->compare.erode_mask,
                    "ignore pixels within N pixels of a silhouette (needs a mask layer)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    app->add_option("--diff", o->diff, "write |a - b| * --diff-scale to this EXR");
    app->add_option("--diff-scale", o->diff_scale, "scale of the difference image")->capture_default_str();
    app->add_flag("--json", o->json, "print the report as JSON on stdout")->capture_default_str();
    command.app = app;
    command.run = [o] { return run_compare(*o); };
    return command;
}

}  // namespace tdf::app
