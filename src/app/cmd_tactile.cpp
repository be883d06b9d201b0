// `tdf tactile <step>`: GelSight captures, height maps and normal maps to tileable tactile
// normal maps at physical scale (spec 6, README "tdf tactile").
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/height_input.h>
#include <tdf/tactile/pipeline.h>

#include <filesystem>
#include <memory>

#include "commands.h"

namespace tdf::app {

namespace {

struct InputArgs {
    std::string source = "auto", image_kind = "auto";
    float mm_per_pixel = 0, image_height_mm = 1.0f;
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
                        "lateral pixel size in mm (0 = from the file: .tmd header or tdf metadata, else "
                        "GelSight Mini 0.085)")
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
        o.image_height_mm = image_height_mm;
        o.invert = invert;
        HeightInput input = load_height_input(path, o);
        log_verbose("{}: {} {}x{}, {} mm per pixel",
                    path,
                    input.kind,
                    input.map.height.width(),
                    input.map.height.height(),
                    input.map.mm_per_pixel);
        return input;
    }
};

Toggle toggle(const std::string& value) {
    return value == "on" ? Toggle::On : value == "off" ? Toggle::Off : Toggle::Auto;
}

struct PatchArgs {
    PatchOptions options;
    std::string filter = "auto", smooth = "auto", contact = "auto";

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
        app->add_option("--smooth", smooth, "bilateral filter: auto (on, off for normal-map inputs), on, off")
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
                        options.size,
                        "patch side after resampling in pixels (0 = keep the crop), at most 4096")
            ->check(CLI::Range(0, 4096))
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
        return o;
    }
};

struct QuiltArgs {
    QuiltOptions options;
    /// `convert` defaults: tileable, min-contrast 0.5 and feather 2 (good maps from any input);
    /// `quilt` defaults to the reference's plain algorithm.
    void add(CLI::App* app, bool convert_defaults) {
        const bool tileable_default = convert_defaults;
        options.tileable = convert_defaults;
        if (convert_defaults) options.min_contrast = 0.5f, options.feather = 2;
        app->add_option("--size",
                        options.size,
                        "output side in pixels (tileable: nearest multiple of the stride), at most 8192")
            ->check(CLI::Range(1, 8192))
            ->capture_default_str();
        app->add_option("--block", options.block, "block side in pixels")
            ->check(CLI::PositiveNumber)
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
    std::string amplitude = "auto";
    float strength = 1.0f;
    int bits = 8;
    bool exr = false;
    void add(CLI::App* app) {
        app->add_option("--amplitude",
                        amplitude,
                        "slope scale: auto (reference for step-1 patches, else physical), reference (spec "
                        "6.4), physical")
            ->check(CLI::IsMember({"auto", "reference", "physical"}))
            ->capture_default_str();
        app->add_option("--strength", strength, "extra factor on the slopes")
            ->check(CLI::PositiveNumber)
            ->capture_default_str();
        app->add_option("--bits", bits, "PNG bit depth")
            ->check(CLI::IsMember({8, 16}))
            ->capture_default_str();
        app->add_flag("--exr", exr, "also write the float normals as <output>.exr");
    }
    void write(const std::string& path, const HeightMap& map) const {
        const Amplitude a = amplitude == "reference"  ? Amplitude::Reference
                            : amplitude == "physical" ? Amplitude::Physical
                                                      : Amplitude::Auto;
        const Image normals = normal_map_from_height(map, a, strength);
        write_normal_map(path, normals, map.mm_per_pixel, map.source, bits);
        if (exr && lower_extension(path) != ".exr")
            write_normal_map(std::filesystem::path(path).replace_extension(".exr").string(),
                             normals,
                             map.mm_per_pixel,
                             map.source);
        log_info("wrote {} ({}x{}, {} mm per pixel, {} x {} mm)",
                 path,
                 normals.width(),
                 normals.height(),
                 map.mm_per_pixel,
                 map.mm_per_pixel * float(normals.width()),
                 map.mm_per_pixel * float(normals.height()));
    }
};

void require_exr(const std::string& path, const char* what) {
    if (lower_extension(path) != ".exr")
        throw_error("{}: {} are written as float EXR; use an .exr output name", path, what);
}

void log_quilt(const QuiltStats& s, const HeightMap& map) {
    log_info("quilted {} blocks ({} candidates); seam error {:.3g} vs {:.3g} for random placement",
             s.blocks_per_side * s.blocks_per_side,
             s.candidates,
             s.mean_cut_error,
             s.mean_random_error);
    log_verbose("quilted map: {}x{}", map.height.width(), map.height.height());
}

// Options of every step; each step reads the ones it registered.
struct State {
    InputArgs input;
    PatchArgs patch;
    QuiltArgs quilt, convert_quilt;
    NormalArgs normal;
    std::string in, out, steps_dir;
    std::vector<std::string> inputs;
    bool no_quilt = false;
    CLI::App *height = nullptr, *patch_cmd = nullptr, *quilt_cmd = nullptr, *normal_cmd = nullptr,
             *convert = nullptr;
};

void run_height(const State& s) {
    require_exr(s.out, "height maps");
    const HeightInput input = s.input.load(s.in);
    write_height_map(s.out, input.map);
    log_info("wrote {} ({}, {}x{}, {} mm per pixel)",
             s.out,
             input.kind,
             input.map.height.width(),
             input.map.height.height(),
             input.map.mm_per_pixel);
}

void run_patch(const State& s) {
    require_exr(s.out, "height patches");
    const HeightMap patch = extract_patch(s.input.load(s.in), s.patch.resolved());
    write_height_map(s.out, patch);
    log_info("wrote {} ({}x{}, {} mm per pixel, height range {} mm)",
             s.out,
             patch.height.width(),
             patch.height.height(),
             patch.mm_per_pixel,
             patch.reference_scale_mm);
}

void run_quilt(const State& s) {
    require_exr(s.out, "quilted height maps");
    std::vector<HeightMap> patches;
    for (const std::string& path : s.inputs) patches.push_back(s.input.load(path).map);
    QuiltStats stats;
    const HeightMap quilted = quilt_height_maps(patches, s.quilt.options, &stats);
    write_height_map(s.out, quilted);
    log_quilt(stats, quilted);
    log_info("wrote {} ({}x{})", s.out, quilted.height.width(), quilted.height.height());
}

void require_normal_map_name(const std::string& path) {
    check_output_extension(path, {".png", ".exr"}, "a normal map (-o)");
}

void run_normal(const State& s) {
    require_normal_map_name(s.out);
    s.normal.write(s.out, s.input.load(s.in).map);
}

void run_convert(const State& s) {
    require_normal_map_name(s.out);
    if (s.no_quilt && s.inputs.size() > 1)
        throw_error("--no-quilt makes a normal map of one patch, but {} inputs were given", s.inputs.size());
    const PatchOptions patch_options = s.patch.resolved();
    const bool steps = !s.steps_dir.empty();
    if (steps) ensure_folder(s.steps_dir);
    auto step_path = [&](const std::string& name) { return s.steps_dir + "/" + name; };
    std::vector<HeightMap> patches;
    for (std::size_t i = 0; i < s.inputs.size(); ++i) {
        PatchSteps figures;
        patches.push_back(
            extract_patch(s.input.load(s.inputs[i]), patch_options, steps ? &figures : nullptr));
        if (!steps) continue;
        const std::string prefix = s.inputs.size() > 1 ? fmt::format("input{}_", i) : "";
        write_height_preview(step_path(prefix + "1_raw_height.png"), figures.raw);
        if (!figures.contact_mask.empty())
            write_png(step_path(prefix + "2_contact_mask.png"), figures.contact_mask);
        write_height_preview(step_path(prefix + "3_high_pass.png"), figures.high_passed);
        if (!figures.smoothed.empty())
            write_height_preview(step_path(prefix + "4_smoothed.png"), figures.smoothed);
        write_height_preview(step_path(prefix + "5_patch.png"), figures.patch);
    }
    HeightMap result = patches[0];
    if (!s.no_quilt) {
        QuiltStats stats;
        result = quilt_height_maps(patches, s.convert_quilt.options, &stats);
        log_quilt(stats, result);
        if (steps) write_height_preview(step_path("6_quilted.png"), result.height);
    }
    s.normal.write(s.out, result);
    if (steps) {  // an 8-bit PNG for viewing, whatever the output's format
        NormalArgs preview = s.normal;
        preview.bits = 8;
        preview.exr = false;
        preview.write(step_path("7_normal_map.png"), result);
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
    s->height->add_option("-o,--output", s->out, "output .exr")->required();
    s->input.add(s->height);

    s->patch_cmd = app->add_subcommand(
        "patch", "height patch: high-pass, smoothing, contact crop, resampling (spec 6.2)");
    s->patch_cmd->add_option("input", s->in, "any input of `tactile height`")->required();
    s->patch_cmd->add_option("-o,--output", s->out, "output .exr (mm, with metadata)")->required();
    s->input.add(s->patch_cmd);
    s->patch.add(s->patch_cmd);

    s->quilt_cmd = app->add_subcommand("quilt", "image quilting of height patches (Efros-Freeman, spec 6.3)");
    s->quilt_cmd
        ->add_option("patches", s->inputs, "height maps (.exr from `tactile patch`, or height images)")
        ->required();
    s->quilt_cmd->add_option("-o,--output", s->out, "output .exr")->required();
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
    s->input.add(s->convert);
    s->patch.add(s->convert);
    s->convert_quilt.add(s->convert, true);
    s->normal.add(s->convert);

    // Global flags (--threads, -q) may follow the step, as they may follow other commands.
    for (CLI::App* step : {s->height, s->patch_cmd, s->quilt_cmd, s->normal_cmd, s->convert})
        step->fallthrough();

    Command command;
    command.app = app;
    command.run = [s]() -> int {
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
