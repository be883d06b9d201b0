// The texture-space optimizer (issue 10): the exported maps after matching reproduce the targets
// laid over the atlas (goal 1), refinement keeps the input's appearance and adds relief-aligned
// detail only where there is relief (goal 2), the whole trainer gradient matches finite
// differences, and the atlas table's gutter and targets behave.
#include <tdf/core/atomic_file.h>
#include <tdf/core/parallel.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/io/image_io.h>
#include <tdf/render/scene_assets.h>
#include <tdf/scene/scene_file.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/train/texture_fidelity.h>
#include <tdf/train/trainer.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace tdf;

namespace {

const std::string kScene = test::source_dir() + "/scenes/pebble_sphere/scene.json";

struct TrainingRun {
    SceneDescription description;
    std::unique_ptr<SceneAssets> assets;
    std::unique_ptr<Trainer> trainer;
    RunConfig config;
};

// The pebble sphere with small renders; the maps at `texture_size`.
TrainingRun make_run(std::vector<std::string> overrides, const std::string& visual = "none", int texture_size = 512,
                     const std::string& scene = kScene) {
    TrainingRun run;
    run.description = load_scene(scene, {});
    run.assets = load_scene_assets(run.description);
    Json merged = {{"optimize",
                    {{"iterations", 40},
                     {"init_iterations", 30},
                     {"resolution", 128},
                     {"patch_resolution", 64},
                     {"batch_size", 2},
                     {"patch_batch_size", 2},
                     {"patch_half_extent", 0.3},
                     {"held_out_views", 3},
                     {"held_out_patches", 3}}},
                   {"export", {{"texture_size", texture_size}}},
                   {"field", Json::object()}};
    for (const std::string& o : overrides) apply_override(merged, o);
    run.config = RunConfig::from_json(merged["optimize"], Json(), merged["export"], Json(), "test", merged["field"]);
    TrainingTarget target;
    target.mesh = &run.assets->mesh;
    target.scene = run.assets->scene.get();
    target.material = &run.assets->material;
    target.prompt = "a pebble sphere";
    run.trainer = std::make_unique<Trainer>(target, run.config, 5);
    run.trainer->set_guidance(GuidanceBackend::create(visual, Json::object()), nullptr);
    return run;
}

std::vector<std::uint8_t> covered_texels(const TexelAtlas& atlas) {
    std::vector<std::uint8_t> covered(atlas.texel_count(), 0);
    for (std::size_t t = 0; t < covered.size(); ++t) covered[t] = atlas.raster.triangle[t] >= 0 ? 1 : 0;
    return covered;
}

// The scene's own maps laid on the sphere's UVs at the map size (bilinear, texel centres), the
// ground truth check_texture_fidelity.py compares with.
Image ground_truth(const std::string& file, int size, bool normals) {
    const Image source = normals ? load_tactile_map(file).normals : read_image(file);
    const MipTexture texture(source);
    Image out(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            float value[kMaxTextureChannels];
            texture.sample_bilinear({(float(x) + 0.5f) / float(size), 1.0f - (float(y) + 0.5f) / float(size)}, value);
            std::copy_n(value, 3, out.pixel(x, y));
        }
    return out;
}

}  // namespace

TEST(TexelAtlas, GutterCopiesItsNearestCoveredTexelAndFoldsGradientsBack) {
    TrainingRun run = make_run({"optimize.iterations=30"}, "none", 128);
    const TexelAtlas& atlas = *run.trainer->texel_atlas();
    Image map(128, 128, 1, 0.0f);
    for (std::size_t k = 0; k < atlas.covered_count(); ++k) map.data()[atlas.texels[k]] = float(k + 1);
    atlas.fill_gutter(map);
    for (std::size_t t = 0; t < atlas.texel_count(); ++t) {
        ASSERT_GE(atlas.source[t], 0) << "texel " << t << " has no source";
        EXPECT_EQ(map.data()[t], float(atlas.source[t] + 1));
    }
    // Adjoint: <fill(x), g> == <x, fold(g)>.
    Image x(128, 128, 1, 0.0f), g(128, 128, 1, 0.0f);
    for (std::size_t t = 0; t < x.pixel_count(); ++t) g.data()[t] = std::sin(float(t));
    for (std::size_t k = 0; k < atlas.covered_count(); ++k) x.data()[atlas.texels[k]] = std::cos(float(k));
    Image filled = x;
    atlas.fill_gutter(filled);
    double lhs = 0, rhs = 0;
    for (std::size_t t = 0; t < x.pixel_count(); ++t) lhs += double(filled.data()[t]) * g.data()[t];
    atlas.fold_gutter_gradient(g);
    for (std::size_t t = 0; t < x.pixel_count(); ++t) rhs += double(x.data()[t]) * g.data()[t];
    EXPECT_NEAR(lhs, rhs, 1e-6 * std::fabs(lhs) + 1e-6);
}

TEST(TextureSpace, MatchingPhaseReproducesTheTargetsOnTheExportedMaps) {
    // Goal 1 on the exported 8-bit maps against the scene's own maps laid on the sphere's UVs.
    TrainingRun run = make_run({"optimize.iterations=30"});
    while (run.trainer->iteration() < run.config.iterations) run.trainer->step();
    const BakedMaps maps = run.trainer->export_maps();
    const std::string folder = test::scratch_dir() + "/texture_space_goal1";
    std::filesystem::create_directories(folder);
    write_png(folder + "/albedo.png", maps.albedo, 8, Quantize::Truncate);
    write_png(folder + "/normal.png", encode_normal_map(maps.tactile_normal), 8, Quantize::Truncate);
    const Image albedo = read_image(folder + "/albedo.png");
    const Image normal = load_tactile_map(folder + "/normal.png").normals;
    const int size = maps.albedo.width();
    const std::string scene_folder = test::source_dir() + "/scenes/pebble_sphere/";
    const TextureFidelity f =
        measure_texture_fidelity(albedo, ground_truth(scene_folder + "albedo.png", size, false), normal,
                                 ground_truth(scene_folder + "tactile_normal.png", size, true),
                                 covered_texels(*run.trainer->texel_atlas()));
    std::printf("after matching: %s\n", f.to_json().dump().c_str());
    EXPECT_GE(f.albedo_psnr, 35.0);
    EXPECT_GE(f.normal_mean_cos, 0.98);
    EXPECT_GE(f.normal_p10_cos, 0.93);
    EXPECT_GE(f.normal_hf_ratio, 0.8);
    EXPECT_LE(f.normal_hf_ratio, 1.25);
    EXPECT_GE(f.albedo_hf_ratio, 0.8);
    EXPECT_LE(f.albedo_hf_ratio, 1.25);
    const QualityReport held_out = run.trainer->evaluate_held_out();
    std::printf("held-out: albedo %.2f dB, tactile cosine %.4f\n", held_out.albedo_psnr_foreground,
                held_out.tactile_mean_cosine);
    EXPECT_GE(held_out.albedo_psnr_foreground, 35.0);
    EXPECT_GE(held_out.tactile_mean_cosine, 0.98);
}

// The pebble sphere with half of its surface untouched: the tactile map is flat for u >= 0.5 and
// the albedo there carries a sharp black-and-white print (a stand-in for a logo or a face).
std::string half_flat_scene() {
    const std::string folder = test::scratch_dir() + "/half_flat";
    std::filesystem::create_directories(folder);
    const std::string source = test::source_dir() + "/scenes/pebble_sphere/";
    Image albedo = read_image(source + "albedo.png");
    Image normals = load_tactile_map(source + "tactile_normal.png").normals;
    const int w = albedo.width(), h = albedo.height();
    for (int y = 0; y < h; ++y)
        for (int x = w / 2; x < w; ++x) {
            float* n = normals.pixel(x, y);
            n[0] = 0, n[1] = 0, n[2] = 1;
            // Print: 6-texel stripes in a band, solid mid-grey elsewhere.
            const bool band = y > h / 4 && y < 3 * h / 4 && x > w / 2 + 16 && x < w - 16;
            const float v = band ? ((x / 6 + y / 12) % 2 ? 0.9f : 0.1f) : 0.55f;
            float* a = albedo.pixel(x, y);
            a[0] = v, a[1] = v * 0.9f, a[2] = v * 0.8f;
        }
    write_png(folder + "/albedo.png", albedo);
    write_png(folder + "/tactile_normal.png", encode_normal_map(normals));
    write_text_atomically(folder + "/scene.json",
                          "{\"mesh\": \"" + source + "sphere.obj\", \"albedo\": {\"source\": \"image\", \"image\": "
                          "\"albedo.png\"}, \"tactile\": {\"images\": [\"tactile_normal.png\"]}}");
    return folder + "/scene.json";
}

TEST(TextureSpace, RefinementAlignsColourWithTheReliefAndKeepsTheInputsColours) {
    // Goals 2 and 4 on the shipped pebble sphere: 30 matching + 70 refinement iterations of
    // 256 px views, default guidance. The seam measure needs refinement to settle and views not
    // far below the default's 512 px: 128 px views after 20 iterations measure 1.2-1.4, after 70
    // 1.14-1.28 depending on the seed; the default run measures 1.03-1.05 (seeds 0 and 5).
    TrainingRun run = make_run({"optimize.iterations=100", "optimize.resolution=256"}, "relief_shading");
    while (run.trainer->iteration() < run.config.iterations) run.trainer->step();
    const BakedMaps maps = run.trainer->export_maps();
    const TextureFidelity f =
        measure_texture_fidelity(maps.albedo, run.trainer->albedo_target(), maps.tactile_normal,
                                 run.trainer->tactile_target(), covered_texels(*run.trainer->texel_atlas()));
    const QualityReport held_out = run.trainer->evaluate_held_out();
    std::printf("pebble after refinement: %s; colour-geometry correlation %.3f\n", f.to_json().dump().c_str(),
                held_out.colour_geometry_correlation);
    EXPECT_GE(f.albedo_psnr_lowpass, 32.0);
    EXPECT_GE(held_out.colour_geometry_correlation, 0.5);
    EXPECT_GE(f.normal_mean_cos, 0.98);
    // Goal 4: the turntable crosses the sphere's u = 0/1 seam; the jump across it is at most 1.2x
    // the steps beside it, for the learned albedo and the learned normals as the viewer sees them.
    std::printf("turntable seams: learned %.3f (input %.3f), normals %.3f (input %.3f) over %zu pairs\n",
                held_out.turntable_seam_jump_ratio_albedo, held_out.turntable_input_seam_jump_ratio_albedo,
                held_out.turntable_seam_jump_ratio_normal, held_out.turntable_input_seam_jump_ratio_normal,
                held_out.turntable_seam_pairs);
    ASSERT_GT(held_out.turntable_seam_pairs, 500u);
    EXPECT_LE(held_out.turntable_seam_jump_ratio_albedo, 1.2);
    EXPECT_LE(held_out.turntable_seam_jump_ratio_normal, 1.2);
    // No 2x2 blocks: views read coarse mip levels, whose adjoint moves blocks of texels together
    // unless the step is smoothed (field.residual_step_smoothing). Steps across block edges (odd
    // columns) against steps inside blocks (even columns): 1.9 unsmoothed, 1.1 smoothed.
    double inside = 0, across = 0;
    const Image& a = maps.albedo;
    for (int y = a.height() / 4; y < 3 * a.height() / 4; ++y)
        for (int x = 0; x + 1 < a.width(); ++x)
            for (int c = 0; c < 3; ++c)
                (x % 2 == 0 ? inside : across) += std::fabs(double(a.at(x + 1, y, c)) - a.at(x, y, c));
    std::printf("albedo steps across 2x2 block edges / inside blocks: %.3f\n", across / inside);
    EXPECT_LE(across / inside, 1.25);
}

TEST(TextureSpace, RefinementKeepsPrintsAndAddsNothingWhereTheReliefIsFlat) {
    const std::string scene = half_flat_scene();
    TrainingRun guided = make_run({"optimize.iterations=50"}, "relief_shading", 512, scene);
    TrainingRun plain = make_run({"optimize.iterations=50"}, "none", 512, scene);
    for (TrainingRun* run : {&guided, &plain})
        while (run->trainer->iteration() < run->config.iterations) run->trainer->step();
    const BakedMaps maps = guided.trainer->export_maps();
    const TextureFidelity f =
        measure_texture_fidelity(maps.albedo, guided.trainer->albedo_target(), maps.tactile_normal,
                                 guided.trainer->tactile_target(), covered_texels(*guided.trainer->texel_atlas()));
    const double with = guided.trainer->evaluate_held_out().colour_geometry_correlation;
    const double without = plain.trainer->evaluate_held_out().colour_geometry_correlation;
    std::printf("half-flat sphere after refinement: %s; colour-geometry correlation %.3f (%.3f without guidance)\n",
                f.to_json().dump().c_str(), with, without);
    ASSERT_GT(f.flat_fraction, 0.2) << "the scene must have flat relief for this check to mean anything";
    EXPECT_GE(f.albedo_psnr_lowpass, 32.0);
    // Where the relief is flat the print keeps its detail and gains none.
    EXPECT_LE(f.albedo_added_hf_flat, 0.05 * f.albedo_hf_flat);
    EXPECT_GT(with, without);  // the print dominates the measure here; the pebble test holds the 0.5
}

TEST(TextureSpace, WholeTrainerGradientMatchesFiniteDifferences) {
    // Refinement iteration without guidance: every term is a smooth function of the maps.
    for (const char* evaluation : {"texture", "pixel"}) {
        TrainingRun run = make_run({"optimize.iterations=4", "optimize.init_iterations=2", "optimize.resolution=48",
                            "optimize.patch_resolution=32", "optimize.max_ssaa=1.5",
                            std::string("field.evaluation=\"") + evaluation + "\""},
                           "none", 64);
        Trainer& trainer = *run.trainer;
        while (trainer.iteration() < 3) trainer.step();
        const int i = trainer.iteration();
        trainer.loss_and_gradient(i);
        const std::vector<float> analytic = trainer.gradient();
        std::vector<float> parameters = trainer.parameters();
        // The largest gradients (they dominate the update) and a spread of others.
        std::vector<std::size_t> order(analytic.size());
        for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
        std::partial_sort(order.begin(), order.begin() + 12, order.end(),
                          [&](std::size_t a, std::size_t b) { return std::fabs(analytic[a]) > std::fabs(analytic[b]); });
        double worst = 0;
        for (int k = 0; k < 12; ++k) {
            const std::size_t p = order[std::size_t(k)];
            const float h = 1e-3f * std::max(1.0f, std::fabs(parameters[p]));
            const float saved = parameters[p];
            parameters[p] = saved + h;
            trainer.set_parameters(parameters);
            const double plus = trainer.loss_and_gradient(i).terms.at("total");
            parameters[p] = saved - h;
            trainer.set_parameters(parameters);
            const double minus = trainer.loss_and_gradient(i).terms.at("total");
            parameters[p] = saved;
            trainer.set_parameters(parameters);
            const double fd = (plus - minus) / (2.0 * double(h));
            const double error = std::fabs(fd - analytic[p]) / std::max(std::fabs(fd), 1e-6);
            worst = std::max(worst, error);
            EXPECT_LT(error, 0.05) << evaluation << " parameter " << p << ": analytic " << analytic[p] << ", finite "
                                   << fd;
        }
        std::printf("%s evaluation: worst relative error of 12 gradients %.4f\n", evaluation, worst);
    }
}

// The export after matching runs with the derived state released (issue 25: the 4096^2 peak);
// what comes back must be the same bits, or the refinement would continue from other maps.
TEST(TextureSpace, ReleasingTheDerivedStateChangesNoBit) {
    for (const char* refine_grid : {"field.refine_grid=false", "field.refine_grid=true"}) {
        SCOPED_TRACE(refine_grid);
        // A colour bound with no tolerance, so that the refinement presses on it (the bound is
        // released too, and must come back the same).
        const std::vector<std::string> overrides = {"optimize.iterations=10", "optimize.init_iterations=6", refine_grid,
                                                    "optimize.albedo_range_lighten=0", "optimize.albedo_range_darken=0"};
        TrainingRun plain = make_run(overrides, "relief_shading", 128);
        TrainingRun released = make_run(overrides, "relief_shading", 128);
        for (TrainingRun* run : {&plain, &released})
            while (run->trainer->iteration() < 6) run->trainer->step();
        released.trainer->release_derived_state();
        const BakedMaps while_released = released.trainer->export_maps();
        EXPECT_EQ(while_released.albedo.values(), plain.trainer->export_maps().albedo.values());
        released.trainer->restore_derived_state();
        EXPECT_EQ(released.trainer->evaluate_held_out().albedo_psnr_foreground,
                  plain.trainer->evaluate_held_out().albedo_psnr_foreground);
        for (TrainingRun* run : {&plain, &released})
            while (run->trainer->iteration() < run->config.iterations) run->trainer->step();
        EXPECT_EQ(released.trainer->parameters(), plain.trainer->parameters());
        const BakedMaps a = plain.trainer->export_maps(), b = released.trainer->export_maps();
        EXPECT_EQ(a.albedo.values(), b.albedo.values());
        EXPECT_EQ(a.tactile_normal.values(), b.tactile_normal.values());
        // The final export releases the levels after finish_training() and rebuilds only them.
        plain.trainer->finish_training();
        released.trainer->finish_training();
        released.trainer->release_derived_state();
        EXPECT_EQ(released.trainer->export_maps().albedo.values(), a.albedo.values());
        released.trainer->restore_derived_state();
        EXPECT_EQ(released.trainer->evaluate_held_out().albedo_psnr_foreground,
                  plain.trainer->evaluate_held_out().albedo_psnr_foreground);
        EXPECT_EQ(released.trainer->evaluate_held_out().tactile_mean_cosine,
                  plain.trainer->evaluate_held_out().tactile_mean_cosine);
    }
}

TEST(TextureSpace, SameFilesOnOneAndTwoThreads) {
    std::vector<float> one, two;
    {
        ThreadLimit limit(1);
        TrainingRun run = make_run({"optimize.iterations=34"}, "relief_shading", 256);
        while (run.trainer->iteration() < run.config.iterations) run.trainer->step();
        one = run.trainer->parameters();
    }
    {
        ThreadLimit limit(2);
        TrainingRun run = make_run({"optimize.iterations=34"}, "relief_shading", 256);
        while (run.trainer->iteration() < run.config.iterations) run.trainer->step();
        two = run.trainer->parameters();
    }
    ASSERT_EQ(one.size(), two.size());
    EXPECT_TRUE(std::equal(one.begin(), one.end(), two.begin()));
}
