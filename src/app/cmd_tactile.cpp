// `tdf tactile <step>`: GelSight captures, height maps and normal maps to tileable tactile
// normal maps at physical scale (spec 6, docs/commands/tactile.md).
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/ambient_occlusion.h>
#include <tdf/tactile/height_export.h>
#include <tdf/tactile/height_input.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/pipeline.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>

#include "commands.h"

namespace tdf::app {

namespace {

struct InputArgs {
    std::string source = "auto", image_kind = "auto";
    float mm_per_pixel = 0, size_mm = 0, image_height_mm = 1.0f;
    bool invert = false;

    void add(CLI::App* app) {
        app->add_option("--source",
                        source,
                        "npz array to use: auto (dm if present), dm, gradients (Poisson-integrated gx/gy)")
            ->check(CLI::IsMember({"auto", "dm", "gradients"}))
            ->capture_default_str();
        app->add_option("--image-kind",
                        image_kind,
                        "image inputs: auto (grey = height, colour = normal map), height, normal")
            ->check(CLI::IsMember({"auto", "height", "normal"}))
            ->capture_default_str();
        app->add_option("--mm-per-pixel",
                        mm_per_pixel,
                        "lateral pixel size in mm (0 = --size-mm, else the file: .tmd header, tdf metadata, "
                        ".npz/.npy = GelSight Mini 0.085; else unknown)")
            ->check(CLI::NonNegativeNumber)
            ->capture_default_str();
        app->add_option("--size-mm", size_mm, "physical width of each input in mm (0 = see --mm-per-pixel)")
            ->check(CLI::NonNegativeNumber)
            ->capture_default_str();
        app->add_option(
               "--height-mm", image_height_mm, "height in mm of a full-scale (white) 8/16-bit height image")
            ->check(CLI::PositiveNumber)
            ->capture_default_str();
        app->add_flag("--invert", invert, "negate heights (the reference's --invert_depth)");
    }
    HeightInput load(const std::string& path) const {
        HeightInputOptions o;
        o.source = source == "dm"          ? CaptureSource::DepthMap
                   : source == "gradients" ? CaptureSource::Gradients
                                           : CaptureSource::Auto;
        o.image_kind = image_kind == "height"   ? ImageKind::Height
                       : image_kind == "normal" ? ImageKind::Normal
                                                : ImageKind::Auto;
        o.mm_per_pixel = mm_per_pixel;
        o.size_mm = size_mm;
        o.image_height_mm = image_height_mm;
        o.invert = invert;
        HeightInput input = load_height_input(path, o);
        log_verbose("{}: {} {}x{}, {} mm per pixel",
                    path,
                    input.kind,
                    input.map.height.width(),
                    input.map.height.height(),
                    input.map.mm_per_pixel > 0 ? fmt::format("{}", input.map.mm_per_pixel) : "unknown");
        return input;
    }
};

Toggle toggle(const std::string& value) {
    return value == "on" ? Toggle::On : value == "off" ? Toggle::Off : Toggle::Auto;
}

struct PatchArgs {
    PatchOptions options;
    std::string filter = "auto", smooth = "auto", contact = "auto", size = "auto";

    void add(CLI::App* app) {
        app->add_option("--filter",
                        filter,
                        "high-pass: auto (fft; gaussian at 1/4 of the width for normal-map inputs), fft "
                        "(reference block filter), "
                        "gaussian (cut-off in mm), none")
            ->check(CLI::IsMember({"auto", "fft", "gaussian", "none"}))
            ->capture_default_str();
        app->add_option("--freq-threshold",
                        options.freq_threshold,
                        "fft filter: half-size of the removed block, in frequency bins")
            ->check(CLI::PositiveNumber)
            ->capture_default_str();
        app->add_option("--cutoff-mm", options.cutoff_mm, "gaussian filter: cut-off wavelength in mm")
            ->check(CLI::PositiveNumber)
            ->capture_default_str();
        app->add_option("--smooth", smooth, "bilateral filter: auto (on for .npz/.npy captures), on, off")
            ->check(CLI::IsMember({"auto", "on", "off"}))
            ->capture_default_str();
        app->add_option("--bilateral-d", options.bilateral_diameter, "bilateral filter diameter in pixels")
            ->check(CLI::PositiveNumber)
            ->capture_default_str();
        app->add_option("--sigma-color", options.sigma_color, "bilateral range sigma (mm)")
            ->capture_default_str();
        app->add_option("--sigma-space", options.sigma_space, "bilateral spatial sigma (pixels)")
            ->capture_default_str();
        app->add_option("--contact",
                        contact,
                        "contact-mask crop: auto (on for .npz/.npy captures), on, off (centre square)")
            ->check(CLI::IsMember({"auto", "on", "off"}))
            ->capture_default_str();
        app->add_option("--depth-threshold",
                        options.depth_threshold,
                        "contact: raw height above which the sensor touches (mm)")
            ->capture_default_str();
        app->add_option("--patch-size",
                        size,
                        "patch side after resampling in pixels: auto (256 for captures, else keep the "
                        "resolution), 0 = keep the crop; at most 4096")
            ->check(CLI::IsMember({"auto"}) | CLI::Range(0, 4096))
            ->capture_default_str();
    }
    PatchOptions resolved() const {
        PatchOptions o = options;
        o.high_pass = filter == "gaussian" ? HighPass::Gaussian
                      : filter == "none"   ? HighPass::None
                      : filter == "fft"    ? HighPass::FftBlock
                                           : HighPass::Auto;
        o.contact = toggle(contact);
        o.smooth = toggle(smooth);
        o.size = size == "auto" ? -1 : std::stoi(size);
        return o;
    }
};

struct QuiltArgs {
    QuiltOptions options;
    std::string block = "40";
    /// `convert` defaults: tileable, min-contrast 0.5 and feather 2 (good maps from any input);
    /// `quilt` defaults to the reference's plain algorithm.
    void add(CLI::App* app, bool convert_defaults) {
        const bool tileable_default = convert_defaults;
        options.tileable = convert_defaults;
        if (convert_defaults) options.min_contrast = 0.9f, options.feather = 2, block = "auto";
        app->add_option(
               "--size", options.size, "output side in pixels (tileable: nearest multiple of the stride), at most 8192")
            ->check(CLI::Range(1, 8192))
            ->capture_default_str();
        app->add_option("--block",
                        block,
                        "block side in pixels, or auto (40 below 512 px patches, else 1/8 of the smallest "
                        "side)")
            ->check(CLI::IsMember({"auto"}) | CLI::PositiveNumber)
            ->capture_default_str();
        app->add_option("--overlap", options.overlap, "overlap as a fraction of the block, (0, 0.5]")
            ->capture_default_str();
        app->add_option(
               "--tolerance", options.tolerance, "accept candidates within (1 + tolerance) x the best error")
            ->capture_default_str();
        app->add_option(
               "--min-contrast",
               options.min_contrast,
               "skip candidate blocks with a standard deviation below this fraction of the median (0 = "
               "reference)")
            ->capture_default_str();
        app->add_option("--min-coverage",
                        options.min_coverage,
                        "use blocks with at least this fraction of their pixels in the textured region")
            ->check(CLI::Range(0.0f, 1.0f))
            ->capture_default_str();
        app->add_option(
               "--feather", options.feather, "blend across cuts over +-N pixels (0 = hard cut, reference)")
            ->check(CLI::NonNegativeNumber)
            ->capture_default_str();
        app->add_option("--seed", options.seed, "random seed")->capture_default_str();
        if (tileable_default)
            app->add_flag(
                "!--no-tileable", options.tileable, "plain (non-wrapping) quilting, like the reference");
        else
            app->add_flag(
                "--tileable", options.tileable, "wrap-around quilting: the output tiles without seams");
    }
};

struct NormalArgs {
    std::string amplitude = "auto", strength = "auto", bits = "auto";
    bool exr = false;
    void add(CLI::App* app) {
        app->add_option("--amplitude",
                        amplitude,
                        "slope scale: auto (reference for step-1 patches of captures, else physical), "
                        "reference (spec 6.4), physical")
            ->check(CLI::IsMember({"auto", "reference", "physical"}))
            ->capture_default_str();
        app->add_option("--strength",
                        strength,
                        "factor on the slopes, or auto: 1 when the slopes are known (normal maps, captures, "
                        "inputs of known size), else the factor giving the textured region 8 degrees")
            ->check(CLI::Validator(
                [](std::string& text) -> std::string {
                    // "auto", or a finite positive number (CLI11's PositiveNumber lets NaN through).
                    if (text == "auto") return {};
                    char* end = nullptr;
                    const double value = std::strtod(text.c_str(), &end);
                    if (end == text.c_str() || *end != '\0' || !std::isfinite(value) || !(value > 0))
                        return "must be auto or a finite number > 0, got " + text;
                    return {};
                },
                "auto|NUMBER > 0"))
            ->capture_default_str();
        app->add_option("--bits",
                        bits,
                        "PNG bit depth: 8, 16, or auto (8, or 16 when 8 bits would lose more than 10 % "
                        "of the mean detail tilt)")
            ->check(CLI::IsMember({"auto", "8", "16"}))
            ->capture_default_str();
        app->add_flag("--exr", exr, "also write the float normals as <output>.exr");
    }
    Amplitude mode() const {
        return amplitude == "reference"  ? Amplitude::Reference
               : amplitude == "physical" ? Amplitude::Physical
                                         : Amplitude::Auto;
    }
    /// The slope factor for maps like `exemplar` (the patch, whose texture mask counts).
    float resolve_strength(const HeightMap& exemplar) const {
        if (strength != "auto") return std::stof(strength);
        const float g = auto_strength(exemplar, mode());
        if (g != 1.0f)
            log_info("{}: --strength auto scales the slopes by {:.3g} (pixel size unknown, so slopes unknown)",
                     exemplar.source,
                     g);
        return g;
    }
    /// The PNG bit depth for `normals` (decoded floats).
    int resolve_bits(const Image& normals) const {
        if (bits != "auto") return std::stoi(bits);
        const double full = material_statistics(detail_slopes(normals), Image(), 90.0).mean_tilt;
        const double eight = material_statistics(detail_slopes(quantized_normals(normals, 8)), Image(), 90.0).mean_tilt;
        const bool sixteen = full > 0 && std::abs(eight - full) > 0.1 * full;
        if (sixteen) log_info("8 bits would change the mean detail tilt from {:.2f} to {:.2f} degrees: writing 16 bits", full, eight);
        return sixteen ? 16 : 8;
    }
    struct Written {
        Image normals;  ///< as a reader of the file decodes them
        int bits = 8;
    };
    Written write(const std::string& path, const HeightMap& map, float slope_factor,
                  const ImageMetadata& extra = {}) const {
        const Image normals = normal_map_from_height(map, mode(), slope_factor);
        Written written;
        const bool png = lower_extension(path) != ".exr";
        written.bits = png ? resolve_bits(normals) : 32;
        written.normals = png ? quantized_normals(normals, written.bits) : normals;
        ImageMetadata metadata = extra;
        metadata["tdf:strength"] = fmt::format("{}", slope_factor);
        write_normal_map(path, normals, map.mm_per_pixel, map.source, png ? written.bits : 8, metadata);
        if (exr && png)
            write_normal_map(std::filesystem::path(path).replace_extension(".exr").string(),
                             normals,
                             map.mm_per_pixel,
                             map.source,
                             8,
                             metadata);
        if (map.mm_per_pixel > 0)
            log_info("wrote {} ({}x{}, {} mm per pixel, {} x {} mm)",
                     path,
                     normals.width(),
                     normals.height(),
                     map.mm_per_pixel,
                     map.mm_per_pixel * float(normals.width()),
                     map.mm_per_pixel * float(normals.height()));
        else
            log_info("wrote {} ({}x{}, mm per pixel unknown)", path, normals.width(), normals.height());
        return written;
    }
};

/// A height map as EXR (mm) or, for a .png name, a 16-bit preview that reads back in mm.
void write_heights(const std::string& path, const HeightMap& map) {
    if (lower_extension(path) == ".png")
        write_height_preview_png(path, map);
    else if (lower_extension(path) == ".exr")
        write_height_map(path, map);
    else
        throw_error("{}: height maps are written as float EXR (or a 16-bit PNG preview): use .exr or .png", path);
}

void log_quilt(const QuiltStats& s, const HeightMap& map) {
    log_info("quilted {} blocks ({} candidates, at least {:.0f} % inside the textured region); seam error {:.3g} vs "
             "{:.3g} for random placement",
             s.blocks_per_side * s.blocks_per_side,
             s.candidates,
             100.0 * s.coverage_needed,
             s.mean_cut_error,
             s.mean_random_error);
    log_verbose("quilted map: {}x{}", map.height.width(), map.height.height());
}

// `--block auto`: 40 px (the reference's example) for patches under 512 px, else an eighth of
// the smallest side (a multiple of 8): large maps keep their resolution and their features
// fit in a block, with few FFT searches over the large exemplar.
QuiltOptions resolve_block(QuiltOptions options, const std::string& block, const std::vector<HeightMap>& patches) {
    if (block != "auto") {
        options.block = std::stoi(block);
        return options;
    }
    int side = std::numeric_limits<int>::max();
    for (const HeightMap& p : patches) side = std::min({side, p.height.width(), p.height.height()});
    options.block = std::max(40, side / 8 / 8 * 8);
    if (options.block != 40) log_info("quilting with {} px blocks (--block auto)", options.block);
    return options;
}

/// The height map the written normals (`decoded`, as a reader of the file sees them) stand for,
/// beside `output` as `<stem>_height.exr` / `_height.png` (issue 24). Returns the scale as JSON.
Json write_convert_height(const std::string& output, const HeightMap& map, const Image& decoded) {
    ExportScale scale;
    scale.periodic = map.tileable;
    scale.mm_per_texel = map.mm_per_pixel > 0 ? map.mm_per_pixel : 1.0f;  // else heights in pixel widths
    ExportedHeight height = export_height(decoded, scale, output);
    height.occlusion = ambient_occlusion(height.map.height, scale.mm_per_texel, scale.periodic);
    height.map.pixel_heights = !(map.mm_per_pixel > 0);
    if (height.map.pixel_heights) height.map.mm_per_pixel = 0;
    const std::string base = (std::filesystem::path(output).parent_path() / std::filesystem::path(output).stem()).string();
    write_exported_height(base, height);
    Json j = exported_height_json(height, scale, std::filesystem::path(base + "_height.png").filename().string(),
                                  std::filesystem::path(base + "_height.exr").filename().string());
    if (height.map.pixel_heights) j["unit"] = "pixel";  // the capture's pixel size is unknown
    log_info("wrote {}_height.exr, .png and _ao.png: {:.4g} .. {:.4g} {} (normals recomputed from it: mean cosine {:.5f})",
             base, height.min_mm, height.max_mm, height.map.pixel_heights ? "pixel widths" : "mm", height.mean_cosine);
    if (height.mean_cosine < kHeightConsistencyLimit)
        log_warning("{}: the height map reproduces the normal map only to a mean cosine of {:.4f} (limit {})", output,
                    height.mean_cosine, kHeightConsistencyLimit);
    return j;
}

// Options of every step; each step reads the ones it registered.
struct State {
    InputArgs input;
    PatchArgs patch;
    QuiltArgs quilt, convert_quilt;
    NormalArgs normal;
    std::string in, out, steps_dir, region_quilt = "off", synthesis = "auto";
    TextureOptimizationOptions optimization;
    std::vector<std::string> inputs;
    bool no_quilt = false;
    CLI::App *height = nullptr, *patch_cmd = nullptr, *quilt_cmd = nullptr, *normal_cmd = nullptr,
             *convert = nullptr;
    CLI::Option* optimize_iterations = nullptr;
};

/// Says when auto smoothing narrowed the window (PatchOptions::smooth).
void log_smoothing(const std::string& input, const PatchSteps& steps, const PatchOptions& options) {
    if (steps.full_window_tilt_loss <= 0) return;
    log_info("{}: smoothing with {}: the {} px window would take {:.0f} % of the contact region's detail tilt (at "
             "most {:.0f} %)",
             input,
             steps.bilateral_diameter > 0 ? fmt::format("a {} px window", steps.bilateral_diameter) : "none",
             options.bilateral_diameter,
             100.0 * steps.full_window_tilt_loss,
             100.0 * kSmoothingMaxTiltLoss);
}

void run_height(const State& s) {
    const HeightInput input = s.input.load(s.in);
    write_heights(s.out, input.map);
    log_info("wrote {} ({}, {}x{})", s.out, input.kind, input.map.height.width(), input.map.height.height());
}

void run_patch(const State& s) {
    PatchSteps steps;
    const HeightMap patch = extract_patch(s.input.load(s.in), s.patch.resolved(), &steps);
    log_smoothing(s.in, steps, s.patch.resolved());
    write_heights(s.out, patch);
    log_info("wrote {} ({}x{}, textured region {:.1f} %, height range {} mm)",
             s.out,
             patch.height.width(),
             patch.height.height(),
             100.0 * mask_fraction(patch.texture_mask),
             patch.reference_scale_mm);
}

void run_quilt(const State& s) {
    std::vector<HeightMap> patches;
    for (const std::string& path : s.inputs) {
        patches.push_back(s.input.load(path).map);
        if (s.region_quilt == "on") {  // the patch file carries no mask: find it again
            HeightMap& p = patches.back();
            p.texture_mask = texture_region(detail_slopes(normal_map_from_height(p)).tilt);
        }
    }
    QuiltStats stats;
    const HeightMap quilted =
        quilt_height_maps(patches, resolve_block(s.quilt.options, s.quilt.block, patches), &stats);
    write_heights(s.out, quilted);
    log_quilt(stats, quilted);
    log_info("wrote {} ({}x{})", s.out, quilted.height.width(), quilted.height.height());
}

void require_normal_map_name(const std::string& path) {
    check_output_extension(path, {".png", ".exr"}, "a normal map (-o)");
    check_output_file_name(path);
}

void run_normal(const State& s) {
    require_normal_map_name(s.out);
    const HeightMap map = s.input.load(s.in).map;
    s.normal.write(s.out, map, s.normal.resolve_strength(map));
}

// convert's first step: each input's patch (its figures kept for the statistics and --steps-png).
std::vector<HeightMap> extract_convert_patches(const State& s, std::vector<PatchSteps>& figures) {
    const PatchOptions patch_options = s.patch.resolved();
    const bool steps = !s.steps_dir.empty();
    auto step_path = [&](const std::string& name) { return s.steps_dir + "/" + name; };
    std::vector<HeightMap> patches;
    figures.assign(s.inputs.size(), PatchSteps{});
    for (std::size_t i = 0; i < s.inputs.size(); ++i) {
        patches.push_back(extract_patch(s.input.load(s.inputs[i]), patch_options, &figures[i]));
        log_info("{}: textured region {:.1f} % of the input ({}), {:.1f} % of the patch",
                 s.inputs[i],
                 100.0 * mask_fraction(figures[i].region),
                 figures[i].contact_mask.empty() ? "local detail tilt" : "contact mask",
                 100.0 * mask_fraction(patches.back().texture_mask));
        log_smoothing(s.inputs[i], figures[i], patch_options);
        if (!steps) continue;
        const std::string prefix = s.inputs.size() > 1 ? fmt::format("input{}_", i) : "";
        const PatchSteps& f = figures[i];
        write_height_preview(step_path(prefix + "1_raw_height.png"), f.raw);
        write_png(step_path(prefix + "2_region.png"), f.region);
        if (!f.contact_mask.empty()) write_png(step_path(prefix + "2_contact_mask.png"), f.contact_mask);
        write_height_preview(step_path(prefix + "3_high_pass.png"), f.high_passed);
        if (!f.smoothed.empty()) write_height_preview(step_path(prefix + "4_smoothed.png"), f.smoothed);
        write_height_preview(step_path(prefix + "5_patch.png"), f.patch);
    }
    return patches;
}

// convert's synthesis: the quilt, or texture optimisation started from it (--synthesis optimize,
// or auto when the quilt misses the material limits by more); `cuts` gets the quilt's seams.
HeightMap synthesize_convert(const State& s, const std::vector<HeightMap>& patches,
                             const std::vector<PatchSteps>& figures, float strength, Image& cuts) {
    const bool steps = !s.steps_dir.empty();
    auto step_path = [&](const std::string& name) { return s.steps_dir + "/" + name; };
    HeightMap result = patches[0];
    QuiltStats stats;
    const QuiltOptions quilt_options = resolve_block(s.convert_quilt.options, s.convert_quilt.block, patches);
    result = quilt_height_maps(patches, quilt_options, &stats, &cuts);
    log_quilt(stats, result);
    // auto: the quilt, unless it misses the limits and texture optimisation misses
    // fewer (docs/commands/tactile.md: the regions of thin rims and lines).
    auto misses = [&](const HeightMap& map) {
        const Image out = normal_map_from_height(map, s.normal.mode(), strength);
        std::vector<MaterialComparison> c;
        for (std::size_t i = 0; i < s.inputs.size(); ++i)
            c.push_back(
                compare_material(scale_normal_slopes(figures[i].input_normals, strength), figures[i].region, out));
        return material_misses(c);
    };
    const double quilt_misses = s.synthesis == "auto" ? misses(result) : 0.0;
    if (s.synthesis == "optimize" || (s.synthesis == "auto" && quilt_misses > 0)) {
        if (steps) write_height_preview(step_path("6_quilted_initial.png"), result.height);
        TextureOptimizationOptions o = s.optimization;
        o.seed = quilt_options.seed;
        o.min_coverage = quilt_options.min_coverage;  // one --min-coverage for blocks and windows
        // The default counts (8 at the coarsest side) follow the sides given.
        if (s.optimize_iterations->count() == 0 && o.iterations.size() > o.windows.size())
            o.iterations.resize(std::max<std::size_t>(o.windows.size(), 1));
        HeightMap optimized = optimize_height_maps(patches, result, o);
        const double optimized_misses = s.synthesis == "auto" ? misses(optimized) : 0.0;
        if (s.synthesis == "auto")
            log_info("the quilt misses the material limits by {:.3f}, texture optimisation by {:.3f}: keeping {}",
                     quilt_misses,
                     optimized_misses,
                     optimized_misses < quilt_misses ? "the optimised map" : "the quilt");
        if (s.synthesis == "optimize" || optimized_misses < quilt_misses) result = std::move(optimized);
    }
    if (steps) write_height_preview(step_path("6_quilted.png"), result.height);
    return result;
}

// What the output keeps of each input's material (docs/commands/tactile.md: statistics), logged,
// warned about and returned as one JSON object per input; `compared` gets the input normals
// the numbers describe.
std::vector<Json> report_convert_material(const State& s, const std::vector<HeightMap>& patches,
                                          const std::vector<PatchSteps>& figures, float strength,
                                          const Image& decoded, std::vector<Image>& compared) {
    std::vector<Json> reports;
    compared.assign(s.inputs.size(), Image());
    for (std::size_t i = 0; i < s.inputs.size(); ++i) {
        // The input's own slopes where they are known: a strength other than 1 shows as a
        // steeper or flatter output, not as an input that changed with it (issue 28).
        const bool known = slopes_known(patches[i], s.normal.mode());
        compared[i] = compared_input_normals(figures[i], patches[i], s.normal.mode(), strength);
        const MaterialComparison c = compare_material(compared[i], figures[i].region, decoded);
        log_info("{}: input's {}mean detail tilt {:.2f} deg (textured region {:.1f} %, {:.1f} % flat); output {:.2f} deg, "
                 "{:.1f} % flat; tilt ratio {:.3f}; texture distance {:.3f}",
                 s.inputs[i],
                 known ? "own " : fmt::format("(slopes unknown, taken at strength {:.3g}) ", strength),
                 c.region.mean_tilt,
                 100.0 * c.region.fraction,
                 100.0 * c.region.flat_fraction,
                 c.output.mean_tilt,
                 100.0 * c.output.flat_fraction,
                 c.tilt_ratio,
                 c.distance);
        MaterialLimits warn;  // "much" flatter or less similar: the yardstick's limits
        warn.min_ratio = 0.75, warn.max_ratio = 1.35;
        for (const std::string& problem : check_material(c, warn))
            log_warning("{}: the output is {}", s.inputs[i], problem);
        // Flatter than the region need not mean flatter than the material: say what the whole
        // input measures when it would fail the same limit.
        if (c.input_tilt_ratio < warn.min_ratio)
            log_info("{}: the input as a whole measures {:.2f} of its region's detail tilt, {:.1f} % flat: the region "
                     "leaves out {:.0f} % of it (flat gel, or smooth parts of the material); a map that keeps the "
                     "whole input's layout measures about that",
                     s.inputs[i],
                     c.input_tilt_ratio,
                     100.0 * c.input_flat,
                     100.0 * (1.0 - c.region.fraction));
        // The comparison's keys, then how the input was taken (docs/commands/tactile.md: report keys).
        Json report = c.to_json();
        report["strength"] = rounded_significant(strength, 4);
        report["input_slopes_known"] = known;
        reports.push_back(std::move(report));
    }
    return reports;
}

// A tileable result: its seam statistics, logged, warned about and kept in the metadata.
void report_convert_seams(const State& s, const HeightMap& result, const Image& cuts, ImageMetadata& metadata) {
    const bool steps = !s.steps_dir.empty();
    auto step_path = [&](const std::string& name) { return s.steps_dir + "/" + name; };
    const SeamStatistics seams = seam_statistics(result.height, cuts);
    log_info("seams: height gradient energy on the cuts {:.2f}x the rest's, step across the wrap {:.2f}x "
             "(columns) and {:.2f}x (rows) the step of the lines next to it{}",
             seams.cut_ratio,
             seams.wrap_ratio_columns,
             seams.wrap_ratio_rows,
             seams.duplicated_border ? ", duplicated border lines" : "");
    if (std::max({seams.cut_ratio, seams.wrap_ratio_columns, seams.wrap_ratio_rows}) > kSeamLimit ||
        seams.duplicated_border)
        log_warning("{}: seams may be visible (limit {:.1f}x the interior)", s.out, kSeamLimit);
    metadata["tdf:seams"] = seams.json();
    if (steps) write_text_atomically(step_path("8_seams.json"), seams.json() + "\n");
}

void run_convert(const State& s) {
    require_normal_map_name(s.out);
    if (s.no_quilt && s.inputs.size() > 1)
        throw_error("--no-quilt makes a normal map of one patch, but {} inputs were given", s.inputs.size());
    if (s.optimization.iterations.size() > s.optimization.windows.size() && s.optimize_iterations->count() > 0)
        throw_error("--optimize-iterations: {} counts for {} window sides (--optimize-windows); give at most one "
                    "per side",
                    s.optimization.iterations.size(),
                    s.optimization.windows.size());
    const bool steps = !s.steps_dir.empty();
    if (steps) ensure_folder(s.steps_dir);
    auto step_path = [&](const std::string& name) { return s.steps_dir + "/" + name; };
    std::vector<PatchSteps> figures;
    const std::vector<HeightMap> patches = extract_convert_patches(s, figures);
    const float strength = s.normal.resolve_strength(patches[0]);  // logs its choice once
    Image cuts;  // where the quilt's boundary cuts run
    HeightMap result = s.no_quilt ? patches[0] : synthesize_convert(s, patches, figures, strength, cuts);
    const Image output = normal_map_from_height(result, s.normal.mode(), strength);
    const bool png = lower_extension(s.out) != ".exr";
    const int bits = png ? s.normal.resolve_bits(output) : 32;
    const Image decoded = png ? quantized_normals(output, bits) : output;
    std::vector<Image> compared;
    const std::vector<Json> reports = report_convert_material(s, patches, figures, strength, decoded, compared);
    for (std::size_t i = 0; i < s.inputs.size() && steps; ++i) {  // the input the numbers describe
        const std::string prefix = s.inputs.size() > 1 ? fmt::format("input{}_", i) : "";
        write_normal_map(step_path(prefix + "0_input_normal.png"),
                         compared[i],
                         patches[i].mm_per_pixel,
                         s.inputs[i],
                         png ? bits : 16);
    }
    const std::string material = reports.size() == 1 ? reports[0].dump() : Json(reports).dump();
    ImageMetadata metadata{{"tdf:material", material}};
    if (!s.no_quilt && result.tileable) report_convert_seams(s, result, cuts, metadata);
    metadata["tdf:height"] = write_convert_height(s.out, result, decoded).dump();
    NormalArgs normal = s.normal;
    normal.bits = png ? std::to_string(bits) : normal.bits;
    normal.write(s.out, result, strength, metadata);
    if (steps) {  // an 8-bit PNG for viewing, whatever the output's format
        NormalArgs preview = s.normal;
        preview.bits = "8";
        preview.exr = false;
        preview.write(step_path("7_normal_map.png"), result, strength, metadata);
        write_text_atomically(step_path("8_statistics.json"), material + "\n");
    }
}

}  // namespace

Command register_tactile(CLI::App& root) {
    auto* app = root.add_subcommand(
        "tactile", "tactile input: GelSight captures / height / normal maps -> tileable normal maps");
    app->require_subcommand(1);

    auto s = std::make_shared<State>();

    s->height =
        app->add_subcommand("height", "any input -> float height map in mm (EXR with mm-per-pixel metadata)");
    s->height->add_option("input", s->in, ".npz/.npy capture, .tmd, height image or normal-map image")
        ->required();
    s->height->add_option("-o,--output", s->out, "output .exr or .png (16-bit preview)")->required();
    s->input.add(s->height);

    s->patch_cmd = app->add_subcommand(
        "patch", "height patch: high-pass, smoothing, contact crop, resampling (spec 6.2)");
    s->patch_cmd->add_option("input", s->in, "any input of `tactile height`")->required();
    s->patch_cmd->add_option("-o,--output", s->out, "output .exr (mm, with metadata) or .png (16-bit preview)")
        ->required();
    s->input.add(s->patch_cmd);
    s->patch.add(s->patch_cmd);

    s->quilt_cmd = app->add_subcommand("quilt", "image quilting of height patches (Efros-Freeman, spec 6.3)");
    s->quilt_cmd
        ->add_option("patches", s->inputs, "height maps (.exr from `tactile patch`, or height images)")
        ->required();
    s->quilt_cmd->add_option("-o,--output", s->out, "output .exr or .png (16-bit preview)")->required();
    s->quilt_cmd
        ->add_option("--region",
                     s->region_quilt,
                     "on: draw blocks only from each patch's textured region (as convert does); off: the "
                     "reference")
        ->check(CLI::IsMember({"on", "off"}))
        ->capture_default_str();
    s->input.add(s->quilt_cmd);
    s->quilt.add(s->quilt_cmd, false);

    s->normal_cmd = app->add_subcommand("normal", "height map -> tangent-space normal map (spec 6.4)");
    s->normal_cmd->add_option("input", s->in, "height map (.exr in mm, or a height image)")->required();
    s->normal_cmd->add_option("-o,--output", s->out, "output .png (or .exr for float normals)")->required();
    s->input.add(s->normal_cmd);
    s->normal.add(s->normal_cmd);

    s->convert =
        app->add_subcommand("convert", "the whole pipeline: input -> patch -> tileable quilt -> normal map");
    s->convert->add_option("inputs", s->inputs, "captures or maps of one material (each becomes an exemplar)")
        ->required();
    s->convert->add_option("-o,--output", s->out, "output normal map .png (or .exr)")->required();
    s->convert->add_option("--steps-png", s->steps_dir, "write a PNG of every step into this folder");
    s->convert->add_flag("--no-quilt", s->no_quilt, "stop after the patch: normal map of the patch itself");
    s->convert
        ->add_option("--synthesis",
                     s->synthesis,
                     "quilt (Efros-Freeman with boundary cuts), optimize (the quilt refined by texture "
                     "optimisation, Kwatra et al. 2005), or auto (optimize when the textured region is too "
                     "thin for whole blocks)")
        ->check(CLI::IsMember({"auto", "quilt", "optimize"}))
        ->capture_default_str();
    s->optimize_iterations =
        s->convert
            ->add_option("--optimize-iterations",
                         s->optimization.iterations,
                         "EM iterations per window side (one per side of --optimize-windows; later sides repeat "
                         "the last)")
            ->check(CLI::PositiveNumber)
            ->capture_default_str();
    s->convert->add_option("--optimize-windows", s->optimization.windows, "window sides, coarse to fine")
        ->capture_default_str();
    s->input.add(s->convert);
    s->patch.add(s->convert);
    s->convert_quilt.add(s->convert, true);
    s->normal.add(s->convert);

    const Command simulate = register_tactile_simulate(*app);

    // Global flags (--threads, -q) may follow the step, as they may follow other commands.
    for (CLI::App* step : {s->height, s->patch_cmd, s->quilt_cmd, s->normal_cmd, s->convert})
        step->fallthrough();

    Command command;
    command.app = app;
    command.run = [s, simulate]() -> int {
        if (simulate.app->parsed()) return simulate.run();
        if (s->height->parsed()) run_height(*s);
        if (s->patch_cmd->parsed()) run_patch(*s);
        if (s->quilt_cmd->parsed()) run_quilt(*s);
        if (s->normal_cmd->parsed()) run_normal(*s);
        if (s->convert->parsed()) run_convert(*s);
        return 0;
    };
    return command;
}

}  // namespace tdf::app
