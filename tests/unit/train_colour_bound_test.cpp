// Issue 29: refinement must not paint light into the albedo. The input's local colour range
// (albedo_range.h), the learned maps' projection into it, and, inside the optimizer on a scene
// with near-black and saturated colours (scenes/dark_bottle), that the final albedo does not
// depend on the training light and stays within its neighbourhood's range.
#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/render/scene_assets.h>
#include <tdf/scene/procedural_mesh.h>
#include <tdf/scene/scene_file.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/train/albedo_range.h>
#include <tdf/train/learned_maps.h>
#include <tdf/train/texel_atlas.h>
#include <tdf/train/trainer.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstdio>

using namespace tdf;

namespace {

TEST(AlbedoRange, WindowStaysInsideItsChart) {
    // 8x8, one channel: left half chart 0 with values 0..3, right half chart 1 at 10.
    Image image(8, 8, 1);
    std::vector<int> label(64);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            image.at(x, y, 0) = x < 4 ? float(x) : 10.0f;
            label[std::size_t(y * 8 + x)] = x < 4 ? 0 : 1;
        }
    label[0] = -1;  // a gutter texel: excluded from every window, keeps its own value
    image.at(0, 0, 0) = -5.0f;
    const ColourRange r = local_colour_range(image, label, 1);
    EXPECT_EQ(r.low.at(3, 4, 0), 2.0f);   // neighbours 2, 3 (x = 4 is the other chart)
    EXPECT_EQ(r.high.at(3, 4, 0), 3.0f);
    EXPECT_EQ(r.low.at(4, 4, 0), 10.0f);  // chart 1 sees only 10s
    EXPECT_EQ(r.low.at(1, 1, 0), 0.0f);   // the gutter's -5 is not a neighbour
    EXPECT_EQ(r.low.at(0, 0, 0), -5.0f);
    const ColourRange wide = local_colour_range(image, label, 3);
    EXPECT_EQ(wide.high.at(0, 4, 0), 3.0f);
}

TEST(AlbedoRange, ExcessMeasuresTheLargestStepOutside) {
    Image input(4, 1, 3, 0.5f), learned(4, 1, 3, 0.5f);
    const std::vector<int> label{0, 0, 0, -1};
    learned.at(1, 0, 2) = 0.58f;  // one channel 0.08 above anything near it
    learned.at(2, 0, 0) = 0.47f;  // 0.03 below
    learned.at(3, 0, 0) = 5.0f;   // gutter: not counted
    const ColourRange range = local_colour_range(input, label, 1);
    const RangeExcess e = measure_range_excess(learned, range, label, 1, 0.05);
    EXPECT_NEAR(e.max_above, 0.08, 1e-6);
    EXPECT_NEAR(e.max_below, 0.03, 1e-6);
    EXPECT_NEAR(e.fraction_above, 1.0 / 3.0, 1e-12);
    EXPECT_EQ(e.fraction_below, 0.0);
}

TEST(AlbedoRange, LearnedMapsProjectIntoTheBoundAndMoveTheResidualWithThem) {
    const TriangleMesh quad = make_quad();
    const TexelAtlas atlas = TexelAtlas::build(quad, 16);
    LearnedMaps maps(atlas);  // field outputs not evaluated: albedo 0.5 from the field
    Image low(16, 16, 3, 0.4f), high(16, 16, 3, 0.6f);
    high.at(3, 3, 1) = 0.9f;
    maps.set_albedo_bounds(low, high);
    for (std::size_t k = 0; k < atlas.covered_count(); ++k) {
        maps.residual()[k * LearnedMaps::kResidualPerTexel + 0] = 0.3f;   // 0.8: above 0.6
        maps.residual()[k * LearnedMaps::kResidualPerTexel + 1] = 0.3f;   // 0.8
        maps.residual()[k * LearnedMaps::kResidualPerTexel + 2] = -0.05f;  // 0.45: inside
    }
    maps.update();
    const Image albedo = maps.export_albedo();
    for (std::size_t k = 0; k < atlas.covered_count(); ++k) {
        const std::size_t t = atlas.texels[k];
        const bool wide = t == 3 * 16 + 3;
        EXPECT_FLOAT_EQ(albedo.data()[3 * t + 0], 0.6f);
        EXPECT_FLOAT_EQ(albedo.data()[3 * t + 1], wide ? 0.8f : 0.6f);
        EXPECT_FLOAT_EQ(albedo.data()[3 * t + 2], 0.45f);
        // The optimizer continues from the projected values.
        EXPECT_FLOAT_EQ(maps.residual()[k * LearnedMaps::kResidualPerTexel + 0], 0.1f);
    }
    maps.set_albedo_bounds(Image(), Image());  // no bound: the values pass through
    maps.residual()[0] = 0.45f;
    maps.update();
    EXPECT_FLOAT_EQ(maps.export_albedo().data()[3 * atlas.texels[0]], 0.95f);
}

TEST(AlbedoRange, BadSettingsNameTheKey) {
    const auto message = [](const Json& optimize) {
        try {
            RunConfig::from_json(optimize, Json(), Json(), Json(), "scene.json").validate("scene.json");
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(message(Json{{"albedo_range_radius", -1}}).find("optimize.albedo_range_radius"), std::string::npos);
    EXPECT_NE(message(Json{{"albedo_range_lighten", 1.5}}).find("optimize.albedo_range_lighten"), std::string::npos);
    EXPECT_NE(message(Json{{"albedo_range_darken", -0.1}}).find("optimize.albedo_range_darken"), std::string::npos);
    EXPECT_NE(message(Json{{"training_light", "sun"}}).find("optimize.training_light"), std::string::npos);
    EXPECT_NE(message(Json{{"training_light", {{"elevation_degrees", 120}}}}).find("optimize.training_light"),
              std::string::npos);
    EXPECT_NE(message(Json{{"training_light", {{"height", 3}}}}).find("height"), std::string::npos);
    EXPECT_EQ(message(Json{{"training_light", "random"}, {"albedo_range_radius", 0}}), "");
}

// A small texture-space run of scenes/dark_bottle: near-black glass and cap, a saturated red
// label with a white logo. Refinement with the default visual guidance (relief_shading).
struct ColourRun {
    std::unique_ptr<SceneAssets> assets;
    std::unique_ptr<Trainer> trainer;
};

ColourRun train(std::vector<std::string> overrides) {
    ColourRun run;
    const SceneDescription description = load_scene(test::source_dir() + "/scenes/dark_bottle/scene.json", {});
    run.assets = load_scene_assets(description);
    Json merged = {{"optimize", {{"iterations", 36}, {"init_iterations", 12}, {"resolution", 96},
                                 {"patch_resolution", 64}, {"batch_size", 2}, {"patch_batch_size", 2},
                                 {"held_out_views", 2}, {"held_out_patches", 2}}},
                   {"export", {{"texture_size", 256}}}};
    for (const std::string& o : overrides) apply_override(merged, o);
    const RunConfig config = RunConfig::from_json(merged["optimize"], Json(), merged["export"], Json(), "test");
    TrainingTarget target;
    target.mesh = &run.assets->mesh;
    target.scene = run.assets->scene.get();
    target.material = &run.assets->material;
    target.prompt = "a dark green glass bottle with a red label";
    run.trainer = std::make_unique<Trainer>(target, config, 7);
    auto tactile = GuidanceBackend::create("exemplar_patch_match", Json::object());
    tactile->set_exemplars({load_tactile_map(description.tactile_images[0]).normals});
    run.trainer->set_guidance(GuidanceBackend::create("relief_shading", Json::object()), std::move(tactile));
    while (run.trainer->iteration() < config.iterations) run.trainer->step();
    return run;
}

struct MapDifference {
    double psnr_db = 0, max_error = 0;
    std::size_t worst_texel = 0;
    double p999 = 0;  ///< 99.9th percentile of the per-channel differences
};

MapDifference difference(const Image& a, const Image& b, const std::vector<int>& label) {
    double squared = 0;
    MapDifference d;
    std::vector<double> errors;
    for (std::size_t t = 0; t < label.size(); ++t) {
        if (label[t] < 0) continue;
        for (int c = 0; c < 3; ++c) {
            const double e = std::fabs(double(a.data()[3 * t + std::size_t(c)]) - double(b.data()[3 * t + std::size_t(c)]));
            squared += e * e;
            errors.push_back(e);
            if (e > d.max_error) d.max_error = e, d.worst_texel = t;
        }
    }
    const double mse = squared / double(errors.size());
    d.psnr_db = mse > 0 ? 10.0 * std::log10(1.0 / mse) : 99.0;
    const auto rank = errors.begin() + std::ptrdiff_t(double(errors.size() - 1) * 0.999);
    std::nth_element(errors.begin(), rank, errors.end());
    d.p999 = *rank;
    return d;
}

TEST(ColourRefinement, TheTrainingLightDoesNotReachTheAlbedo) {
    // The same views (the random light is still drawn), lit from the upper left in one run and
    // from the lower right, closer, in the other. The relief-aligned colour is a relative change of
    // the input's own colour, learned through the shade: the albedo must come out the same.
    // Stated tolerance, over the covered texels of the two final albedo maps: PSNR >= 45 dB, the
    // 99.9th percentile of the per-channel differences <= 0.03, none above 0.1 (at 256^2 a texel
    // on the edge of a printed letter straddles red and white, and there the views' footprints
    // weigh its neighbours by their shade: measured 0.061 at one such texel). The additive relief
    // of the earlier backend, learned as detail / shade, failed it on this scene: 44.8 dB, 99.9th
    // percentile 0.055, max 0.27 (a dark-glass texel, input 0.05 0.10 0.06, came out 0.36 red
    // under one light and 0.63 under the other).
    const ColourRun a = train({R"(optimize.training_light={"elevation_degrees":60,"azimuth_degrees":135,"distance":4})"});
    const ColourRun b = train({R"(optimize.training_light={"elevation_degrees":35,"azimuth_degrees":-60,"distance":3})"});
    const Image albedo_a = a.trainer->export_maps().albedo, albedo_b = b.trainer->export_maps().albedo;
    const std::vector<int>& label = a.trainer->texel_charts();
    const MapDifference between = difference(albedo_a, albedo_b, label);
    const MapDifference moved = difference(albedo_a, a.trainer->albedo_target(), label);
    const Image& input = a.trainer->albedo_target();
    const std::size_t w = between.worst_texel;
    std::printf("two training lights: final albedo maps %.1f dB apart (99.9th percentile %.4f, max %.4f at texel "
                "%zu: input %.3f %.3f %.3f, light a %.3f %.3f %.3f, light b %.3f %.3f %.3f); refinement moved the "
                "albedo %.1f dB from the input (max %.4f)\n",
                between.psnr_db, between.p999, between.max_error, w, input.data()[3 * w], input.data()[3 * w + 1],
                input.data()[3 * w + 2], albedo_a.data()[3 * w], albedo_a.data()[3 * w + 1], albedo_a.data()[3 * w + 2],
                albedo_b.data()[3 * w], albedo_b.data()[3 * w + 1], albedo_b.data()[3 * w + 2], moved.psnr_db,
                moved.max_error);
    EXPECT_LT(moved.psnr_db, 90.0) << "refinement changed nothing: the test would pass by mistake";
    EXPECT_GE(between.psnr_db, 45.0);
    EXPECT_LE(between.p999, 0.03);
    EXPECT_LE(between.max_error, 0.1);
}

TEST(ColourRefinement, DarkStaysDarkSaturatedStaysSaturated) {
    const ColourRun run = train({});
    const Image albedo = run.trainer->export_maps().albedo;
    const RangeExcess e = run.trainer->albedo_range_excess(albedo);
    std::printf("dark_bottle: max above the input's local max %.4f, below its local min %.4f (limit %.2f)\n",
                e.max_above, e.max_below, e.limit);
    EXPECT_LE(e.max_above, 0.05);  // issue 29: nothing brighter than its neighbourhood + 0.05
    // Saturated texels (the red label, the yellow rules: HSV saturation >= 0.8, value >= 0.3)
    // keep a saturation of at least 0.75: light painted in turns them pale (the earlier backend
    // left white spots on the label), relief-aligned colour only scales them.
    const Image& input = run.trainer->albedo_target();
    const auto saturation = [](const float* c) {
        const float high = std::max({c[0], c[1], c[2]}), low = std::min({c[0], c[1], c[2]});
        return high > 0.0f ? (high - low) / high : 0.0f;
    };
    std::size_t saturated = 0, paled = 0;
    float lowest = 1.0f;
    for (std::size_t t = 0; t < run.trainer->texel_charts().size(); ++t) {
        const float* in = input.data() + 3 * t;
        if (run.trainer->texel_charts()[t] < 0 || saturation(in) < 0.8f || std::max({in[0], in[1], in[2]}) < 0.3f)
            continue;
        ++saturated;
        const float s = saturation(albedo.data() + 3 * t);
        lowest = std::min(lowest, s);
        paled += s < 0.75f;
    }
    std::printf("saturated texels: %zu, lowest saturation after refinement %.3f, %zu below 0.75\n", saturated, lowest,
                paled);
    ASSERT_GT(saturated, 1000u) << "the scene must have saturated colour for this check to mean anything";
    EXPECT_EQ(paled, 0u);
}

}  // namespace
