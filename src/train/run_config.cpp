#include <tdf/train/run_config.h>

#include <tdf/core/error.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/material_sampling.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

template <typename T>
T choose(ConfigReader& reader, const std::string& key, T fallback,
         std::initializer_list<std::pair<const char*, T>> choices) {
    if (!reader.has(key)) return fallback;
    const std::string value = reader.require<std::string>(key);
    std::string valid;
    for (const auto& [name, choice] : choices) {
        if (value == name) return choice;
        valid += valid.empty() ? name : std::string(", ") + name;
    }
    throw_error("{}: '{}' must be one of {}, got '{}'", reader.where(), key, valid, value);
}

// optimize.training_light: "random" (the default) or a fixed light {elevation_degrees,
// azimuth_degrees, distance}.
void read_training_light(ConfigReader& r, const std::string& source, RunConfig& c) {
    if (!r.has("training_light")) return;
    const Json& light = r.raw("training_light");
    if (light.is_string() && light.get<std::string>() == "random") {
        c.fixed_training_light = false;
    } else if (light.is_object()) {
        ConfigReader lr(light, source + ": optimize.training_light");
        c.fixed_training_light = true;
        c.light_elevation_degrees = lr.get("elevation_degrees", c.light_elevation_degrees);
        c.light_azimuth_degrees = lr.get("azimuth_degrees", c.light_azimuth_degrees);
        c.light_distance = lr.get("distance", c.light_distance);
        lr.check_all_read();
    } else {
        throw_error("{}: optimize.training_light must be \"random\" or an object "
                    "{{\"elevation_degrees\", \"azimuth_degrees\", \"distance\"}}", source);
    }
}

// The guidance section is validated by the backends themselves; here only the names.
void read_guidance_names(const Json& guidance, const std::string& source, RunConfig& c) {
    if (guidance.is_object()) {
        const std::vector<std::string> backends = GuidanceBackend::names();
        for (auto it = guidance.begin(); it != guidance.end(); ++it) {
            const std::string& key = it.key();
            const bool known = key == "visual" || key == "tactile" || key == "save_frames" ||
                               std::find(backends.begin(), backends.end(), key) != backends.end();
            if (!known)
                throw_error("{}: guidance: unknown key '{}' (expected visual, tactile, save_frames or a backend name)",
                            source, key);
        }
        c.guidance_config = guidance;
        if (guidance.contains("visual")) {
            if (!guidance["visual"].is_string()) throw_error("{}: guidance.visual must be a backend name", source);
            c.guidance_visual = guidance["visual"].get<std::string>();
        }
        if (guidance.contains("tactile")) {
            if (!guidance["tactile"].is_string()) throw_error("{}: guidance.tactile must be a backend name", source);
            c.guidance_tactile = guidance["tactile"].get<std::string>();
        }
        if (guidance.contains("save_frames")) {
            if (!guidance["save_frames"].is_boolean()) throw_error("{}: guidance.save_frames must be true or false", source);
            c.save_guidance_frames = guidance["save_frames"].get<bool>();
        }
    } else if (!guidance.is_null()) {
        throw_error("{}: 'guidance' must be an object", source);
    }
}

}  // namespace

RunConfig RunConfig::from_json(const Json& optimize, const Json& tactile_layout, const Json& exporting,
                               const Json& guidance, const std::string& source, const Json& field,
                               const Json& schedule) {
    RunConfig c;
    if (!schedule.is_null()) {
        if (!schedule.is_string()) throw_error("{}: 'schedule' must be \"texture\" or \"reference\"", source);
        c.schedule = schedule.get<std::string>();
        if (c.schedule == "reference") {
            c.evaluation = FieldEvaluation::Pixel;
            c.iterations = 200;  // 150 + 50
            c.init_iterations = 150;
            c.visual_guidance_loss = "l1_structural";
            c.weights.albedo_refine = 500.0f;
            c.max_ssaa = 2.0f;
        } else if (c.schedule != "texture") {
            throw_error("{}: 'schedule' must be \"texture\" or \"reference\", got '{}'", source, c.schedule);
        }
    }
    ConfigReader fr(field, source + ": field");
    c.evaluation = choose(fr, "evaluation", c.evaluation,
                          {{"texture", FieldEvaluation::Texture}, {"pixel", FieldEvaluation::Pixel}});
    c.table_log2 = fr.get("table_log2", c.table_log2);
    c.refine_grid = fr.get("refine_grid", c.refine_grid);
    c.fit_texels = fr.get("fit_texels", c.fit_texels);
    c.residual_optimizer = fr.get("residual_optimizer", c.residual_optimizer);
    c.residual_step = fr.get("residual_step", c.residual_step);
    c.residual_step_smoothing = fr.get("residual_step_smoothing", c.residual_step_smoothing);
    c.tactile_seam_band = fr.get("tactile_seam_band", c.tactile_seam_band);
    fr.check_all_read();
    if (c.evaluation == FieldEvaluation::Pixel && !schedule.is_string()) {
        // Pixel evaluation without a schedule named: the reference's losses.
        c.visual_guidance_loss = "l1_structural";
        c.weights.albedo_refine = 500.0f;
        c.max_ssaa = 2.0f;
    }
    ConfigReader r(optimize, source + ": optimize");
    c.iterations = r.get("iterations", c.iterations);
    c.init_iterations = r.get("init_iterations", c.init_iterations);
    c.batch_size = r.get("batch_size", c.batch_size);
    c.patch_batch_size = r.get("patch_batch_size", c.patch_batch_size);
    c.resolution = r.get("resolution", c.resolution);
    if (c.evaluation != FieldEvaluation::Texture) c.patch_resolution_auto = false;  // the reference's 512
    if (r.has("patch_resolution")) {
        const Json& value = r.raw("patch_resolution");
        if (value.is_string()) {
            if (value.get<std::string>() != "auto")
                throw_error("{}: optimize.patch_resolution must be a size in pixels or \"auto\", got '{}'",
                            source, value.get<std::string>());
            c.patch_resolution_auto = true;
        } else {
            c.patch_resolution = r.get("patch_resolution", c.patch_resolution);
            c.patch_resolution_auto = false;
        }
    }
    c.patch_half_extent = r.get("patch_half_extent", c.patch_half_extent);
    c.patch_distance = r.get("patch_distance", c.patch_distance);
    c.max_ssaa = r.get("max_ssaa", c.max_ssaa);
    c.learning_rate = r.get("learning_rate", c.learning_rate);
    read_training_light(r, source, c);
    c.albedo_range_radius = r.get("albedo_range_radius", c.albedo_range_radius);
    c.albedo_range_lighten = r.get("albedo_range_lighten", c.albedo_range_lighten);
    c.albedo_range_darken = r.get("albedo_range_darken", c.albedo_range_darken);
    c.checkpoint_every = r.get("checkpoint_every", c.checkpoint_every);
    c.held_out_views = r.get("held_out_views", c.held_out_views);
    c.held_out_patches = r.get("held_out_patches", c.held_out_patches);
    c.field_raw_coordinates = r.get("field_raw_coordinates", c.field_raw_coordinates);
    c.visual_guidance_loss = r.get("visual_guidance_loss", c.visual_guidance_loss);
    c.tactile_guidance_loss = choose(r, "tactile_guidance_loss", c.tactile_guidance_loss,
                                     {{"cosine", TactileGuidanceLoss::Cosine}, {"mse", TactileGuidanceLoss::Mse}});
    ConfigReader w = r.child("weights");
    LossWeights& lw = c.weights;
    lw.albedo_init = w.get("albedo_init", lw.albedo_init);
    lw.albedo_refine = w.get("albedo_refine", lw.albedo_refine);
    lw.tactile_init = w.get("tactile_init", lw.tactile_init);
    lw.tactile_refine = w.get("tactile_refine", lw.tactile_refine);
    lw.tactile_guidance = w.get("tactile_guidance", lw.tactile_guidance);
    lw.visual_guidance = w.get("visual_guidance", lw.visual_guidance);
    lw.visual_guidance_structural = w.get("visual_guidance_structural", lw.visual_guidance_structural);
    lw.texture_albedo = w.get("texture_albedo", lw.texture_albedo);
    lw.texture_tactile = w.get("texture_tactile", lw.texture_tactile);
    w.check_all_read();
    r.check_all_read();

    ConfigReader t(tactile_layout, source + ": tactile_layout");
    c.tactile_layout = choose(t, "mode", c.tactile_layout,
                              {{"atlas", TactileLayout::Atlas}, {"physical", TactileLayout::Physical}});
    c.mm_per_unit = t.get("mm_per_unit", c.mm_per_unit);
    c.tactile_mm_per_pixel = t.get("mm_per_pixel", c.tactile_mm_per_pixel);
    t.check_all_read();

    ConfigReader e(exporting, source + ": export");
    c.texture_size = e.get("texture_size", c.texture_size);
    c.gutter = e.get("gutter", c.gutter);
    c.write_glb = e.get("glb", c.write_glb);
    c.write_exr = e.get("exr", c.write_exr);
    c.height_metric = choose(e, "height_texel_size", c.height_metric,
                             {{"map", HeightMetric::Map}, {"surface", HeightMetric::Surface}});
    c.turntable_views = e.get("turntable_views", c.turntable_views);
    c.turntable_resolution = e.get("turntable_resolution", c.turntable_resolution);
    e.check_all_read();

    read_guidance_names(guidance, source, c);
    c.validate(source);
    return c;
}

void RunConfig::validate(const std::string& source) const {
    const auto positive = [&](const char* key, double value) {
        if (!(value > 0)) throw_error("{}: {} must be positive, got {}", source, key, value);
    };
    positive("optimize.iterations", iterations);
    positive("optimize.batch_size", batch_size);
    positive("optimize.patch_batch_size", patch_batch_size);
    positive("optimize.resolution", resolution);
    positive("optimize.patch_resolution", patch_resolution);
    positive("optimize.learning_rate", learning_rate);
    positive("optimize.patch_half_extent", patch_half_extent);
    positive("optimize.patch_distance", patch_distance);
    positive("export.texture_size", texture_size);
    if (init_iterations < 0 || init_iterations > iterations)
        throw_error("{}: optimize.init_iterations must be in [0, iterations={}], got {}", source, iterations,
                    init_iterations);
    if (resolution > 8192 || patch_resolution > 8192 || texture_size > 16384)
        throw_error("{}: resolutions above 8192 (16384 for textures) are not supported", source);
    if (!(max_ssaa >= 1.0f && max_ssaa <= 4.0f))
        throw_error("{}: optimize.max_ssaa must be in [1, 4], got {}", source, max_ssaa);
    if (gutter < 0) throw_error("{}: export.gutter must be >= 0, got {}", source, gutter);
    if (albedo_range_radius < 0 || albedo_range_radius > 64)
        throw_error("{}: optimize.albedo_range_radius must be in [0, 64] texels (0 = no bound), got {}", source,
                    albedo_range_radius);
    if (!(albedo_range_lighten >= 0.0f && albedo_range_lighten <= 1.0f))
        throw_error("{}: optimize.albedo_range_lighten must be in [0, 1], got {}", source, albedo_range_lighten);
    if (!(albedo_range_darken >= 0.0f && albedo_range_darken <= 1.0f))
        throw_error("{}: optimize.albedo_range_darken must be in [0, 1], got {}", source, albedo_range_darken);
    if (fixed_training_light &&
        !(light_elevation_degrees >= 0.0f && light_elevation_degrees <= 90.0f && std::isfinite(light_azimuth_degrees) &&
          light_distance > 0.0f && light_distance <= 100.0f))
        throw_error("{}: optimize.training_light needs elevation_degrees in [0, 90], a finite azimuth_degrees and "
                    "distance in (0, 100]",
                    source);
    if (checkpoint_every < 0) throw_error("{}: optimize.checkpoint_every must be >= 0", source);
    if (held_out_views < 0 || held_out_patches < 0) throw_error("{}: held-out counts must be >= 0", source);
    if (turntable_views < 0) throw_error("{}: export.turntable_views must be >= 0", source);
    if (tactile_layout == TactileLayout::Physical && !(mm_per_unit > 0))
        throw_error("{}: tactile_layout.mode=physical needs tactile_layout.mm_per_unit > 0 (millimetres per mesh unit)",
                    source);
    if (residual_optimizer != "jacobi" && residual_optimizer != "adam")
        throw_error("{}: field.residual_optimizer must be \"jacobi\" or \"adam\", got '{}'", source, residual_optimizer);
    if (!(residual_step > 0.0f && residual_step <= 1.0f))
        throw_error("{}: field.residual_step must be in (0, 1], got {}", source, residual_step);
    if (residual_step_smoothing < 0 || residual_step_smoothing > 8)
        throw_error("{}: field.residual_step_smoothing must be in [0, 8], got {}", source, residual_step_smoothing);
    if (!(tactile_seam_band >= 0.0f && tactile_seam_band <= 64.0f))
        throw_error("{}: field.tactile_seam_band must be in [0, 64] texels, got {}", source, tactile_seam_band);
    if (visual_guidance_loss != "mse" && visual_guidance_loss != "l1_structural")
        throw_error("{}: optimize.visual_guidance_loss must be \"mse\" or \"l1_structural\", got '{}'", source,
                    visual_guidance_loss);
    if (table_log2 < 10 || table_log2 > 24)
        throw_error("{}: field.table_log2 must be in [10, 24], got {}", source, table_log2);
    if (fit_texels < 1024 || fit_texels > (1 << 24))
        throw_error("{}: field.fit_texels must be in [1024, 16777216], got {}", source, fit_texels);
    const float all_weights[] = {weights.albedo_init,      weights.albedo_refine,    weights.tactile_init,
                                 weights.tactile_refine,   weights.tactile_guidance, weights.visual_guidance,
                                 weights.visual_guidance_structural, weights.texture_albedo, weights.texture_tactile};
    for (float v : all_weights)
        if (!(v >= 0.0f)) throw_error("{}: loss weights must be >= 0 and finite", source);
}

double patch_window_texels(const TriangleMesh& mesh, const RunConfig& config) {
    if (!mesh.has_uvs()) return 0.0;
    double units_per_uv_unit = 0.0;
    try {
        units_per_uv_unit = mesh_units_per_uv_unit(mesh);
    } catch (const Error&) {
        return 0.0;  // no UV area
    }
    const double texels =
        2.0 * double(config.patch_half_extent) * double(config.texture_size) / units_per_uv_unit;
    return std::isfinite(texels) ? texels : 0.0;
}

int auto_patch_resolution(const TriangleMesh& mesh, const RunConfig& config) {
    constexpr int kReference = 512, kSmallest = 64, kStep = 32;
    const double texels = patch_window_texels(mesh, config);
    const double pixels = std::ceil(double(kAutoPatchPixelsPerTexel) * texels / kStep) * kStep;
    if (!(texels > 0.0) || pixels >= double(kReference)) return kReference;
    return std::max(kSmallest, int(pixels));
}

Json RunConfig::to_json() const {
    Json j;
    j["optimize"] = {
        {"iterations", iterations},
        {"init_iterations", init_iterations},
        {"batch_size", batch_size},
        {"patch_batch_size", patch_batch_size},
        {"resolution", resolution},
        {"patch_resolution", patch_resolution},
        {"patch_half_extent", patch_half_extent},
        {"patch_distance", patch_distance},
        {"max_ssaa", max_ssaa},
        {"learning_rate", learning_rate},
        {"training_light", fixed_training_light ? Json{{"elevation_degrees", light_elevation_degrees},
                                                       {"azimuth_degrees", light_azimuth_degrees},
                                                       {"distance", light_distance}}
                                                : Json("random")},
        {"albedo_range_radius", albedo_range_radius},
        {"albedo_range_lighten", albedo_range_lighten},
        {"albedo_range_darken", albedo_range_darken},
        {"checkpoint_every", checkpoint_every},
        {"held_out_views", held_out_views},
        {"held_out_patches", held_out_patches},
        {"field_raw_coordinates", field_raw_coordinates},
        {"tactile_guidance_loss", tactile_guidance_loss == TactileGuidanceLoss::Cosine ? "cosine" : "mse"},
        {"visual_guidance_loss", visual_guidance_loss},
        {"weights",
         {{"albedo_init", weights.albedo_init},
          {"albedo_refine", weights.albedo_refine},
          {"tactile_init", weights.tactile_init},
          {"tactile_refine", weights.tactile_refine},
          {"tactile_guidance", weights.tactile_guidance},
          {"visual_guidance", weights.visual_guidance},
          {"visual_guidance_structural", weights.visual_guidance_structural},
          {"texture_albedo", weights.texture_albedo},
          {"texture_tactile", weights.texture_tactile}}}};
    j["schedule"] = schedule;
    j["field"] = {{"evaluation", evaluation == FieldEvaluation::Texture ? "texture" : "pixel"},
                  {"table_log2", table_log2},
                  {"refine_grid", refine_grid},
                  {"fit_texels", fit_texels},
                  {"residual_optimizer", residual_optimizer},
                  {"residual_step", residual_step}, {"residual_step_smoothing", residual_step_smoothing},
                  {"tactile_seam_band", tactile_seam_band}};
    j["tactile_layout"] = {{"mode", tactile_layout == TactileLayout::Atlas ? "atlas" : "physical"},
                           {"mm_per_unit", mm_per_unit},
                           {"mm_per_pixel", tactile_mm_per_pixel}};
    j["export"] = {{"texture_size", texture_size},
                   {"gutter", gutter},
                   {"glb", write_glb},
                   {"exr", write_exr},
                   {"height_texel_size", height_metric == HeightMetric::Map ? "map" : "surface"},
                   {"turntable_views", turntable_views},
                   {"turntable_resolution", turntable_resolution}};
    Json g = guidance_config;
    g["visual"] = guidance_visual;
    g["tactile"] = guidance_tactile;
    g["save_frames"] = save_guidance_frames;
    j["guidance"] = g;
    return j;
}

}  // namespace tdf
