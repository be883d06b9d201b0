#include <tdf/train/optimize_run.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/core/progress.h>
#include <tdf/guidance/exemplar_patch_match.h>
#include <tdf/guidance/schedule.h>
#include <tdf/io/image_io.h>
#include <tdf/parts/part_target.h>
#include <tdf/optim/checkpoint.h>
#include <tdf/render/scene_assets.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/train/albedo_spots.h>
#include <tdf/train/asset_export.h>
#include <tdf/train/asset_height.h>
#include <tdf/train/tactile_roundtrip.h>
#include <tdf/train/part_gating.h>
#include <tdf/train/part_quality.h>
#include <tdf/train/run_report.h>
#include <tdf/train/run_guard.h>
#include <tdf/train/texture_fidelity.h>
#include <tdf/train/trainer.h>

#include <fmt/format.h>

#include <cctype>
#include <chrono>
#include <filesystem>
#include <set>
#include <sys/resource.h>

namespace tdf {

namespace fs = std::filesystem;

namespace {

// "avocado_00000" -> "avocado": texture names in the reference's description table.
std::string texture_name_of(const std::string& path) {
    std::string stem = fs::path(path).stem().string();
    const auto cut = stem.find("_");
    return cut == std::string::npos ? stem : stem.substr(0, cut);
}

std::string make_prompt(const std::string& object_name, const std::string& tactile_path) {
    const std::string texture = texture_name_of(tactile_path);
    try {
        return textured_prompt(object_name, texture);
    } catch (const Error&) {
        // A texture outside the reference's table: its own name describes it.
        return object_words(object_name) + " with " + texture + " texture" + kPromptSuffix;
    }
}

// Words of a file or node name: split at '_', '-', '.' and spaces, then at lower-to-upper case
// changes, lower-cased, without digit-only tokens and words that name the file rather than the
// object (checked before and after the case split: "RichDreamer", "WaterBottleMesh").
std::string name_words(const std::string& name) {
    static const std::set<std::string> kGeneric = {
        "mesh",     "model",  "scene", "object",       "obj",       "gltf",     "glb",       "ply",
        "untitled", "export", "final", "triangulated", "triangles", "textured", "decimated", "simplified",
        "remeshed", "lowpoly", "highpoly", "base",     "geometry",  "richdreamer", "instantmesh", "node", "root"};
    const auto lower = [](std::string t) {
        for (char& c : t) c = char(std::tolower(static_cast<unsigned char>(c)));
        return t;
    };
    const auto keep = [&](const std::string& t) {
        return !t.empty() && !kGeneric.count(lower(t)) && t.find_first_not_of("0123456789") != std::string::npos;
    };
    std::vector<std::string> tokens(1);
    for (const char c : name) {
        if (c == '_' || c == '-' || c == '.' || std::isspace(static_cast<unsigned char>(c)))
            tokens.emplace_back();
        else
            tokens.back().push_back(c);
    }
    std::string words;
    for (const std::string& token : tokens) {
        if (!keep(token)) continue;
        std::vector<std::string> parts(1);
        for (std::size_t i = 0; i < token.size(); ++i) {
            const bool camel = i > 0 && std::isupper(static_cast<unsigned char>(token[i])) &&
                               std::islower(static_cast<unsigned char>(token[i - 1]));
            if (camel) parts.emplace_back();
            parts.back().push_back(token[i]);
        }
        for (const std::string& part : parts)
            if (keep(part)) words += (words.empty() ? "" : " ") + lower(part);
    }
    return words;
}

}  // namespace

std::string object_name_for_prompt(const SceneDescription& d, const TriangleMesh& mesh) {
    if (!d.object_name.empty()) return d.object_name;
    // The mesh file's stem ("Avocado.gltf", the reference's "<obj>/<obj>_mesh.obj").
    std::string words = name_words(fs::path(d.mesh).stem().string());
    if (!words.empty()) return words;
    // A generic file name ("scene.gltf", "model.obj"): the input's one named node or object.
    std::set<std::string> objects;
    for (const FaceGroup& g : mesh.face_groups)
        if (!name_words(g.object).empty()) objects.insert(name_words(g.object));
    if (objects.size() == 1) return *objects.begin();
    // The reference's choice (spec 1.1): the mesh file's folder.
    words = name_words(fs::path(d.mesh).parent_path().filename().string());
    return words.empty() ? "object" : words;
}

namespace {

// `override_config` (a part's guidance.config) replaces the run's guidance.<name> when not null.
std::unique_ptr<GuidanceBackend> make_backend(const std::string& name, const RunConfig& config,
                                              const std::vector<std::string>& tactile_images,
                                              const Json& override_config = Json()) {
    Json backend_config = Json::object();
    if (config.guidance_config.contains(name)) backend_config = config.guidance_config[name];
    if (!override_config.is_null()) backend_config = override_config;
    auto backend = GuidanceBackend::create(name, backend_config);
    if (backend && !backend_config.contains("exemplars")) {
        // The scene's own tactile maps are the touched exemplars unless the config names others.
        std::vector<Image> exemplars;
        for (const std::string& path : tactile_images) exemplars.push_back(load_tactile_map(path).normals);
        backend->set_exemplars(std::move(exemplars));
    }
    return backend;
}

// Texture-space fidelity of the maps as just exported (`maps`, not exported again) against the
// targets laid over the atlas (issue 10's goals 1 and 2), over the covered texels; null for
// pixel evaluation.
Json texture_space_quality(const Trainer& trainer, const BakedMaps& maps) {
    const TexelAtlas* atlas = trainer.texel_atlas();
    if (!atlas) return Json();
    std::vector<std::uint8_t> covered(atlas->texel_count(), 0);
    for (std::uint32_t t : atlas->texels) covered[t] = 1;
    Json quality = measure_texture_fidelity(maps.albedo, trainer.albedo_target(), maps.tactile_normal,
                                            trainer.tactile_target(), covered)
                       .to_json();
    // Issue 29: light painted into the albedo shows as texels brighter than anything near them
    // in the input (or darker than anything near them).
    quality["albedo_local_range"] = trainer.albedo_range_excess(maps.albedo).to_json();
    return quality;
}

// The after-matching albedo at the report's spots (issue 29); none when this process did not run
// the matching phase's end (a resumed run) or without a texel atlas (pixel evaluation).
struct MatchedSpots {
    std::vector<AlbedoSpot> spots;
    std::vector<Image> crops;  // per spot, the after-matching albedo's window
};

// The window of the input's darkest and brightest spot (issue 29) and the after-matching albedo's
// crops there: all of the after-matching map the final report needs.
MatchedSpots matched_spots(const Trainer& trainer, const Image& matched_albedo) {
    MatchedSpots matched;
    if (!trainer.texel_atlas()) return matched;  // pixel evaluation: no texture-space report
    const Image& input = trainer.albedo_target();
    const int window = std::max(8, input.width() / 16);
    matched.spots = find_albedo_spots(input, trainer.texel_charts(), window);
    for (const AlbedoSpot& spot : matched.spots) matched.crops.push_back(albedo_spot_crop(spot, matched_albedo));
    return matched;
}

// Issue 29's three numbers against their aims, and the spot crops the report page shows (input |
// after matching | final at the input's darkest and brightest spot, `<base>_albedo_spot_*.png`).
Json colour_check(const Trainer& trainer, const Image& final_albedo, const MatchedSpots& matched,
                  const std::string& base, const QualityReport& quality, const Json& texture) {
    const Json& range = texture["albedo_local_range"];
    const double lowpass = texture["albedo_psnr_lowpass_db"].get<double>();
    const double above = range["max_above_local_max"].get<double>();
    Json colour = {
        {"albedo_psnr_lowpass_db", lowpass},
        {"colour_geometry_correlation", quality.colour_geometry_correlation},
        {"added_colour_geometry_correlation", quality.added_colour_geometry_correlation},
        {"max_above_local_max", above},
        {"aims", {{"albedo_psnr_lowpass_db", ">= 33"}, {"added_colour_geometry_correlation", ">= 0.4"},
                  {"max_above_local_max", "<= 0.05"}}},
        {"met", {{"albedo_psnr_lowpass_db", lowpass >= 33.0},
                 {"added_colour_geometry_correlation", quality.added_colour_geometry_correlation >= 0.4},
                 {"max_above_local_max", above <= kRangeMeasureLimit}}},
        {"spots", Json::array()}};
    const Image& input = trainer.albedo_target();
    for (std::size_t i = 0; i < matched.spots.size(); ++i) {
        const AlbedoSpot& spot = matched.spots[i];
        const std::string file = fmt::format("{}_albedo_spot_{}.png", base, spot.name);
        write_png(file, albedo_spot_strip(albedo_spot_crop(spot, input), matched.crops[i],
                                          albedo_spot_crop(spot, final_albedo), std::max(1, 256 / spot.size)));
        colour["spots"].push_back({{"name", spot.name},
                                   {"file", std::filesystem::path(file).filename().string()},
                                   {"texel", {spot.x, spot.y}},
                                   {"size", spot.size},
                                   {"input_luminance", spot.luminance}});
    }
    return colour;
}

const Json& section(const SceneDescription& d, const char* name) {
    static const Json kNull;
    const auto it = d.sections.find(name);
    return it == d.sections.end() ? kNull : it->second;
}

}  // namespace

PartTraining prepare_part_training(const SceneDescription& description, const TriangleMesh& mesh,
                                   const SurfaceMaterial& material, int size, int gutter, const std::string& where) {
    PartSegmentationInput input;
    input.mesh = &mesh;
    input.atlas = &mesh;  // the trained maps use the mesh's own UVs
    input.material = &material;
    input.size = size;
    input.seed = description.seed;
    input.where = where;
    PartTraining parts;
    parts.segmentation = segment_parts(description.parts, input);
    parts.layers = lay_scene_part_maps(description.parts, mesh, size, where).layers;
    parts.target = compose_part_target(parts.segmentation.texel_part, size, parts.layers, kDefaultPartBand, gutter);
    return parts;
}

namespace {

// The process's peak resident memory so far (Linux reports ru_maxrss in KiB).
double peak_memory_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0;
}

// One `tdf optimize` run's inputs and what its stages hand each other.
struct OptimizeRun {
    const OptimizeOptions& options;
    SceneDescription description;
    RunConfig config;
    std::string name;  // file prefix
    std::string base;  // output_dir/name
    std::unique_ptr<SceneAssets> assets;
    TrainingTarget target;
    Json resolved;        // the scene with the resolved configuration (<name>_config.json)
    Json inputs;          // run safety: every input's hash
    std::unique_ptr<PartTraining> parts;  // multi-part only
    std::string checkpoint_path;
    LossLog log;
    MatchedSpots matched_spots;  // the after-matching albedo's crops for the report (issue 29)
    // Multi-part: the learned normal map at the part boundaries after matching (bleed is
    // meaningful then, when the map equals the composed target; refinement changes texels everywhere).
    Json boundary_after_matching;
    std::vector<PartQuality> quality_after_matching;  // the report's parts[] (part_quality.h)
    FaceMaterials face_materials;  // multi-part: one material (and glTF primitive) per part
    // Wall seconds per stage of the job, in the order they ran, and the process's peak memory at
    // each stage's end (the report's `stages`: where a run's time and memory go).
    struct Stage {
        std::string name;
        double seconds = 0;
        double peak_mb = 0;
    };
    std::vector<Stage> stages;
    std::chrono::steady_clock::time_point stage_start = std::chrono::steady_clock::now();

    explicit OptimizeRun(const OptimizeOptions& o)
        : options(o),
          description(load_scene(o.scene_path, o.overrides)),
          config(RunConfig::from_json(section(description, "optimize"), section(description, "tactile_layout"),
                                      section(description, "export"), section(description, "guidance"), o.scene_path,
                                      section(description, "field"), section(description, "schedule"))),
          checkpoint_path(o.output_dir + "/checkpoint.bin") {
        if (description.tactile_images.empty())
            throw_error("{}: the scene names no tactile texture (tactile.images); `tdf optimize` needs one", o.scene_path);
        name = o.name.empty() ? fs::absolute(o.scene_path).parent_path().filename().string() : o.name;
        base = o.output_dir + "/" + name;
    }

    // Ends the stage running since the previous call (or the start) and names it.
    void end_stage(const std::string& stage) {
        const auto now = std::chrono::steady_clock::now();
        const double seconds = std::chrono::duration<double>(now - stage_start).count();
        stage_start = now;
        const double peak_mb = peak_memory_mb();
        for (Stage& s : stages)
            if (s.name == stage) {
                s.seconds += seconds;
                s.peak_mb = peak_mb;
                return;
            }
        stages.push_back({stage, seconds, peak_mb});
    }
    Json stages_json() const {
        Json j = Json::array();
        for (const Stage& s : stages) j.push_back({{"stage", s.name}, {"seconds", s.seconds}, {"peak_mb", s.peak_mb}});
        return j;
    }

    void save_checkpoint(const Trainer& trainer) const {
        const Json extra = {{"inputs", inputs}, {"iteration", trainer.iteration()},  // run safety: input hashes
                            {"seed", description.seed},
                            {"config", resolved.dump()},
                            {"losses", log.to_json_lines()}};
        save_field_checkpoint(checkpoint_path, trainer.checkpoint_pieces(), extra.dump());
    }
    void write_log() const {
        write_text_atomically(base + "_losses.jsonl", log.to_json_lines());
        write_text_atomically(base + "_loss_plot.svg", log.to_svg(config.init_iterations));
    }
    // How the learned normal map handles the part boundaries (measure_part_boundary against each
    // part's own laid map).
    Json boundary_json(const BakedMaps& m) const {
        const PartBoundaryMeasure b = measure_part_boundary(m.tactile_normal, parts->segmentation.texel_part,
                                                            parts->segmentation.size, parts->layers);
        return Json{{"bleed_texels", b.bleed_texels},
                    {"boundary_step_degrees", b.boundary_step_degrees},
                    {"hard_cut_step_degrees", b.hard_step_degrees},
                    {"band_detail_ratio", b.band_detail_ratio}};
    }
    std::vector<PartQuality> part_quality(const BakedMaps& m, const std::vector<int>& predicted) const {
        const PartSegmentation& seg = parts->segmentation;
        return measure_part_quality(m.tactile_normal, parts->target, seg.texel_part, predicted, seg.size,
                                    parts->layers, seg.part_names);
    }
};

// The scene's assets, the training target, the resolved configuration and the input hashes; a
// refused resume stops here, before anything is written.
void load_inputs(OptimizeRun& run) {
    const RunConfig& config = run.config;
    const SceneDescription& description = run.description;
    run.assets = load_scene_assets(description);
    if (config.patch_resolution_auto)
        run.config.patch_resolution = auto_patch_resolution(run.assets->mesh, config);
    {
        // The reference's cameras (radius 1.25-2.25, 0.15-unit patches, spec 2.3-2.4) assume a mesh
        // of about unit size centred at the origin; its base meshes are (training uses raw coordinates).
        const Bounds3 bounds = compute_bounds(run.assets->mesh);
        const Vec3f e = bounds.extent();
        const float largest = std::max(e.x, std::max(e.y, e.z));
        if (largest > 4.0f || largest < 0.5f || length(bounds.center()) > 0.5f * largest)
            log_warning("{}: the mesh spans {:.3g} units around ({:.3g}, {:.3g}, {:.3g}); the training cameras "
                        "expect about [-1, 1]: set \"normalize\": true in the scene", description.mesh, largest,
                        bounds.center().x, bounds.center().y, bounds.center().z);
    }
    TrainingTarget& target = run.target;
    target.mesh = &run.assets->mesh;
    target.scene = run.assets->scene.get();
    target.material = &run.assets->material;
    target.prompt = make_prompt(object_name_for_prompt(description, run.assets->mesh), description.tactile_images.front());
    run.resolved = description.to_json();
    const Json config_json = config.to_json();
    for (auto it = config_json.begin(); it != config_json.end(); ++it) run.resolved[it.key()] = *it;
    run.inputs = hash_input_files(scene_input_files(description, guidance_exemplar_files(config.guidance_config)));
    if (run.options.resume) verify_resume(run.checkpoint_path, run.resolved.dump(), run.inputs);
}

// The first file of the run, written once the inputs (parts included) are known good: bad
// input leaves nothing.
void write_resolved_config(const OptimizeRun& run) {
    write_text_atomically(run.base + "_config.json", run.resolved.dump(2) + "\n");
    log_info("tdf optimize: scene {}, seed {}, {} iterations ({} matching), resolved configuration in {}_config.json",
             run.options.scene_path, run.description.seed, run.config.iterations, run.config.init_iterations, run.base);
    log_info("prompt: \"{}\"", run.target.prompt);
}

// Multi-part: the segmentation and the composed target (docs/multi-part-textures.md).
void prepare_parts(OptimizeRun& run) {
    if (!run.description.parts.enabled()) return;
    const RunConfig& config = run.config;
    if (config.evaluation != FieldEvaluation::Texture)
        throw_error("{}: multi-part scenes need field.evaluation=texture (pixel evaluation has no part support)",
                    run.options.scene_path);
    run.parts = std::make_unique<PartTraining>(prepare_part_training(run.description, run.assets->mesh,
                                                                     run.assets->material, config.texture_size,
                                                                     config.gutter, run.options.scene_path + ": parts"));
    const PartSegmentation& seg = run.parts->segmentation;
    run.target.tactile_target_override = &run.parts->target;
    run.target.texel_parts = &seg.texel_part;
    run.target.part_names = seg.part_names;
    run.face_materials = {seg.part_names, seg.face_part};
    std::string summary;
    for (std::size_t p = 0; p < seg.part_count(); ++p)
        summary += fmt::format("{}{} {:.1f} %", p ? ", " : "", seg.part_names[p], 100.0 * seg.part_fraction[p]);
    log_info("parts ({}): {}", run.description.parts.source.kind, summary);
}

// The guidance backends: visual, and tactile once or (multi-part) per part with the part's own
// maps as exemplars and its own settings (parts.list[i].guidance), gated by the part's mask.
void attach_guidance(Trainer& trainer, const OptimizeRun& run) {
    const RunConfig& config = run.config;
    const SceneDescription& description = run.description;
    if (trainer.tactile_seam_blend().seam_edges > 0)
        log_info("tactile map across UV seams: {} seam edges, {} texels cross-faded within {} texels "
                 "(field.tactile_seam_band)",
                 trainer.tactile_seam_blend().seam_edges, trainer.tactile_seam_blend().blended_texels,
                 config.tactile_seam_band);
    auto visual = make_backend(config.guidance_visual, config, description.tactile_images);
    std::unique_ptr<GuidanceBackend> tactile;
    bool tactile_on = false;
    if (run.parts) {
        std::vector<PartGuidance> part_guidance;
        for (std::size_t k = 0; k < description.parts.parts.size(); ++k) {
            const PartSpec& spec = description.parts.parts[k];
            PartGuidance g;
            g.name = spec.name;
            g.prompt = spec.prompt;
            g.settings = PartGuidanceSettings::from_json(
                spec.guidance, fmt::format("{}: parts.list[{}].guidance", run.options.scene_path, k));
            const std::string backend = g.settings.backend.empty() ? config.guidance_tactile : g.settings.backend;
            g.backend = make_backend(backend, config, spec.tactile_images, g.settings.backend_config);
            tactile_on = tactile_on || g.backend;
            part_guidance.push_back(std::move(g));
        }
        trainer.set_part_guidance(std::move(part_guidance));
    } else {
        tactile = make_backend(config.guidance_tactile, config, description.tactile_images);
        tactile_on = tactile != nullptr;
    }
    if (!visual || !tactile_on)
        log_info("guidance: {}{}; the refinement phase uses the matching terms only for what is disabled",
                 visual ? "" : "visual off ", tactile_on ? "" : "tactile off");
    trainer.set_guidance(std::move(visual), std::move(tactile));
    const double window_texels = patch_window_texels(run.assets->mesh, config);
    log_info("tactile patches: {:.2f} pixels per tactile map texel ({} px over {:.4g} mesh units{})",
             trainer.pixels_per_texel(), config.patch_resolution, 2.0 * double(config.patch_half_extent),
             config.patch_resolution_auto && window_texels > 0.0
                 ? fmt::format("; optimize.patch_resolution=auto: {:.1f} px per learned-map texel, the "
                               "reference's 512 px {:.1f}",
                               config.patch_resolution / window_texels, 512.0 / window_texels)
                 : "");
    if (config.save_guidance_frames) trainer.save_guidance_frames_to(run.options.output_dir + "/guidance_frames");
}

// --resume: the trainer and the loss log from the checkpoint.
void resume_from_checkpoint(Trainer& trainer, OptimizeRun& run) {
    const std::string& path = run.checkpoint_path;
    if (!fs::exists(path)) throw_error("--resume: no checkpoint at '{}' (start without --resume)", path);
    const FieldCheckpoint checkpoint = load_field_checkpoint(path);
    const Json extra = parse_json(checkpoint.extra, path);
    if (!extra.contains("config") || extra["config"].get<std::string>() != run.resolved.dump())
        throw_error("--resume: '{}' was written with a different scene or configuration", path);
    const int iteration = extra["iteration"].get<int>();
    trainer.restore(iteration, checkpoint.parameters, checkpoint.adam);
    run.log = LossLog::from_json_lines(extra["losses"].get<std::string>(), path);
    run.log.truncate(iteration);
    log_info("resuming at iteration {} from {}", iteration, path);
}

// The end of the matching phase: the asset as matched (`_initialized`), its quality report (the
// issue's measure is taken here) and, multi-part, the boundary measure. The asset is written
// (its height solve is the run's peak at large maps) while the trainer holds only what the
// refinement cannot rebuild exactly.
void export_matched(Trainer& trainer, OptimizeRun& run, const TriangleMesh& export_mesh) {
    trainer.release_derived_state();
    BakedMaps matched_maps = trainer.export_maps();
    const ExportScale height_scale = asset_export_scale(*run.assets, export_mesh, run.config);  // issue 24
    write_asset(run.options.output_dir, run.name, "_initialized", matched_maps, export_mesh, run.config,
                run.face_materials, &height_scale);
    // The texture-space measure reads only the maps, the targets' level 0 and the atlas: taken
    // before the derived state comes back, so its map-sized buffers do not add to it.
    const Json texture = texture_space_quality(trainer, matched_maps);
    trainer.restore_derived_state();
    run.end_stage("export_matched");
    const QualityReport matched = trainer.evaluate_held_out();
    Json initialized = {{"quality", matched.to_json()}, {"iteration", trainer.iteration()}};
    if (!texture.is_null()) initialized["texture_space"] = texture;
    write_text_atomically(run.base + "_initialized_report.json", initialized.dump(2) + "\n");
    if (run.parts) {
        run.boundary_after_matching = run.boundary_json(matched_maps);
        run.quality_after_matching = run.part_quality(matched_maps, {});
    }
    run.end_stage("evaluate_matched");
    log_info("after matching: albedo PSNR {:.2f} dB (held-out views, foreground), tactile mean cosine {:.4f}",
             matched.albedo_psnr_foreground, matched.tactile_mean_cosine);
    run.matched_spots = matched_spots(trainer, matched_maps.albedo);  // for the final report's spot crops
}

// The iterations, with checkpoints at phase ends and every checkpoint_every. Returns false when
// the run stopped before its last iteration (--stop-after), with a checkpoint to resume from.
bool train(Trainer& trainer, OptimizeRun& run, ProgressReporter& progress, const TriangleMesh& export_mesh) {
    const RunConfig& config = run.config;
    // Texture evaluation: a matching iteration fits the grid on texels (no rendering), a
    // refinement iteration renders 8 views and calls guidance: measured about 12x the cost.
    if (config.init_iterations < config.iterations)
        progress.add_phase(std::size_t(config.init_iterations),
                           config.evaluation == FieldEvaluation::Texture ? 12.0 : 1.5);
    progress.start_at(std::size_t(trainer.iteration()));
    const int last_iteration =
        run.options.stop_after > 0 ? std::min(run.options.stop_after, config.iterations) : config.iterations;
    while (trainer.iteration() < last_iteration) {
        LossRecord record;
        try {
            record = trainer.step();
        } catch (const Error& e) {
            progress.finish();
            run.write_log();
            throw_error("{}; the last good checkpoint is '{}' (continue with --resume)", e.what(), run.checkpoint_path);
        }
        run.log.add(record);
        const int done = trainer.iteration();
        std::string status;
        for (const auto& [term, value] : record.terms) status += fmt::format(" {}={:.4g}", term, value);
        progress.advance(1, status);
        const bool phase_end = done == config.init_iterations || done == config.iterations;
        if (phase_end || (config.checkpoint_every > 0 && done % config.checkpoint_every == 0)) {
            run.save_checkpoint(trainer);
            run.write_log();
        }
        if (done == config.init_iterations && config.init_iterations < config.iterations) {
            progress.finish();
            run.end_stage("matching");
            export_matched(trainer, run, export_mesh);
        }
        if (stop_requested()) break;  // run safety: a stop signal ends the run at this iteration boundary
    }
    progress.finish();
    run.write_log();
    run.end_stage(trainer.iteration() > config.init_iterations ? "refinement" : "matching");
    if (trainer.iteration() >= config.iterations) return true;
    run.save_checkpoint(trainer);
    if (stop_requested()) throw_interrupted(trainer.iteration(), run.checkpoint_path);  // run safety
    log_info("stopped after iteration {} as asked; continue with --resume", trainer.iteration());
    return false;
}

// Multi-part: the label head's prediction at the texels (the exported label map) and the
// segmentation's, their agreement, and the boundary measures.
Json part_report(const Trainer& trainer, OptimizeRun& run, const BakedMaps& maps, const std::vector<int>& predicted) {
    const PartSegmentation& seg = run.parts->segmentation;
    const RunConfig& config = run.config;
    Json report = seg.report(run.description.parts);
    report["label_head_trained"] = trainer.trains_labels();
    report["legend"] = write_part_maps(run.base, predicted, seg.size, seg.part_names, config.gutter);
    report["segmentation_legend"] =
        write_part_maps(run.base + "_segmentation", seg.texel_part, seg.size, seg.part_names, config.gutter);
    std::size_t agree = 0, labelled = 0;
    for (std::size_t t = 0; t < predicted.size(); ++t)
        if (seg.texel_part[t] >= 0) ++labelled, agree += predicted[t] == seg.texel_part[t];
    report["label_agreement"] = labelled ? double(agree) / double(labelled) : 0.0;
    if (config.init_iterations == config.iterations) run.boundary_after_matching = run.boundary_json(maps);
    if (!run.boundary_after_matching.is_null()) report["boundary_after_matching"] = run.boundary_after_matching;
    report["boundary_final"] = run.boundary_json(maps);
    log_info("parts: label map agrees with the segmentation on {:.2f} % of covered texels; {}_label_map.png, "
             "{}_label_legend.json, {}_mask_<part>.png",
             100.0 * report["label_agreement"].get<double>(), run.name, run.name, run.name);
    return report;
}

// The finished asset, its turntable, <name>_report.json and <name>_report.html.
void export_final(Trainer& trainer, OptimizeRun& run, const ProgressReporter& progress,
                  const TriangleMesh& export_mesh) {
    const RunConfig& config = run.config;
    trainer.finish_training();
    trainer.release_derived_state();  // the mip levels, while the asset is written (as after matching)
    const BakedMaps maps = trainer.export_maps();
    const ExportScale height_scale = asset_export_scale(*run.assets, export_mesh, config);  // issue 24
    const Json height_json =
        write_asset(run.options.output_dir, run.name, "", maps, export_mesh, config, run.face_materials, &height_scale);
    trainer.restore_derived_state();
    run.end_stage("export");
    const QualityReport quality = trainer.evaluate_held_out();
    run.end_stage("evaluate");
    write_turntable(run.options.output_dir, run.assets->mesh, *run.assets->scene, maps, config.turntable_views,
                    config.turntable_resolution);
    run.end_stage("turntable");
    Json report = {{"quality", quality.to_json()},
                   {"seconds_per_iteration", trainer.stage_times().to_json(trainer.iteration())},
                   {"seconds_total", progress.elapsed_seconds()},
                   {"seed", run.description.seed},
                   {"threads", ThreadLimit::current()}};
    if (!height_json.is_null()) report["height_map"] = height_json;
    if (const Json touch = tactile_roundtrip(run.options.output_dir, *run.assets, run.description.parts, height_scale,
                                                   run.description.seed);
        !touch.is_null())
        report["tactile_roundtrip"] = touch;
    if (const Json texture = texture_space_quality(trainer, maps); !texture.is_null()) {
        report["texture_space"] = texture;
        report["colour"] = colour_check(trainer, maps.albedo, run.matched_spots, run.base, quality, texture);
    }
    if (run.parts) {
        const std::vector<int> predicted = trainer.predicted_texel_parts();
        report["part_segmentation"] = part_report(trainer, run, maps, predicted);
        report["parts"] = write_part_report_entries(run.base, run.part_quality(maps, predicted),
                                                    run.quality_after_matching, run.parts->layers);
    }
    run.end_stage("measures");
    report["stages"] = run.stages_json();  // the page below is timed by its own log line
    write_text_atomically(run.base + "_report.json", report.dump(2) + "\n");
    log_info("held-out quality: albedo PSNR {:.2f} dB (foreground), tactile mean cosine {:.4f}; report in {}_report.json",
             quality.albedo_psnr_foreground, quality.tactile_mean_cosine, run.base);
    write_optimize_report(run.options.output_dir, run.name, run.options.scene_path, *run.assets, config);
    run.end_stage("report_page");
    std::string line;
    for (const auto& stage : run.stages)
        line += fmt::format("{}{} {:.1f}", line.empty() ? "" : ", ", stage.name, stage.seconds);
    log_info("stages (wall s): {}; peak memory {:.0f} MB", line, run.stages.back().peak_mb);
}

}  // namespace

void run_optimize(const OptimizeOptions& options) {
    OptimizeRun run(options);
    // Run safety (docs/commands/optimize.md "Runs that survive"): lock, temporaries, completion record.
    const RunGuard guard(options.output_dir, run.name, "optimize");
    load_inputs(run);
    prepare_parts(run);
    write_resolved_config(run);
    Trainer trainer(run.target, run.config, run.description.seed);
    attach_guidance(trainer, run);
    if (options.resume) resume_from_checkpoint(trainer, run);
    run.end_stage("setup");
    // Exports go back to the input's coordinates (the scene may normalise the mesh for training).
    const TriangleMesh export_mesh = run.assets->export_mesh();
    ProgressReporter progress("optimize", std::size_t(run.config.iterations), 10);
    if (!train(trainer, run, progress, export_mesh)) return;
    export_final(trainer, run, progress, export_mesh);
    guard.complete({{"report", run.name + "_report.json"}});  // run safety: the completion record, written last
}

}  // namespace tdf
