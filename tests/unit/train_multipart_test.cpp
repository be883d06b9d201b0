// Multi-part texturing in the texture-space optimizer (issue 14): on the shipped two-part sphere,
// the label head learns the parts, the learned normal map carries each part's own tactile map
// and neither material bleeds into the other beyond 2 texels.
#include <tdf/core/error.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/parts/part_target.h>
#include <tdf/render/scene_assets.h>
#include <tdf/scene/scene_file.h>
#include <tdf/train/optimize_run.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/train/part_gating.h>
#include <tdf/train/trainer.h>

#include "common/four_part_sphere.h"
#include "common/spot_truth.h"
#include "common/part_training.h"
#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

using namespace tdf;

namespace {

const std::string kFolder = test::source_dir() + "/scenes/two_part_sphere/";

// A tactile guidance backend for the gating test: wherever its mask is positive it asks for one
// strongly tilted view-space normal, a "material" no part has, so what it changed is easy to find.
class TiltBackend : public GuidanceBackend {
public:
    std::string name() const override { return "tilt"; }
    bool supports(GuidanceKind kind) const override { return kind == GuidanceKind::Tactile; }
    GuidanceResult refine(const GuidanceRequest& request) override {
        GuidanceResult result;
        for (std::size_t k = 0; k < request.images.size(); ++k) {
            Image refined = request.images[k];
            for (std::size_t p = 0; p < refined.pixel_count(); ++p)
                if (request.masks[k].data()[p] > 0.0f) {
                    refined.data()[3 * p] = 0.6f;
                    refined.data()[3 * p + 1] = 0.0f;
                    refined.data()[3 * p + 2] = 0.8f;
                }
            result.refined.push_back(std::move(refined));
        }
        ++calls;
        return result;
    }
    int calls = 0;
};

// Per texel, the centre distance to the nearest texel labelled `part` within `radius` texels
// (1e9 beyond).
std::vector<double> distance_to_part(const std::vector<int>& labels, int size, int part, int radius) {
    std::vector<double> d(labels.size(), 1e9);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            for (int dy = -radius; dy <= radius; ++dy)
                for (int dx = -radius; dx <= radius; ++dx) {
                    const int u = x + dx, v = y + dy;
                    if (u < 0 || v < 0 || u >= size || v >= size) continue;
                    if (labels[std::size_t(v) * std::size_t(size) + std::size_t(u)] != part) continue;
                    double& out = d[std::size_t(y) * std::size_t(size) + std::size_t(x)];
                    out = std::min(out, std::sqrt(double(dx * dx + dy * dy)));
                }
    return d;
}

double angle_degrees(const Image& a, const Image& b, std::size_t t) {
    const Vec3f na = safe_normalize(Vec3f{a.data()[3 * t], a.data()[3 * t + 1], a.data()[3 * t + 2]});
    const Vec3f nb = safe_normalize(Vec3f{b.data()[3 * t], b.data()[3 * t + 1], b.data()[3 * t + 2]});
    return std::acos(std::clamp(double(dot(na, nb)), -1.0, 1.0)) * 180.0 / 3.14159265358979;
}

}  // namespace

TEST(TextureSpaceParts, FourPartsLabelsBoundariesAndGatedGuidance) {
    const SceneDescription two = load_scene(kFolder + "scene.json");
    const auto assets = load_scene_assets(two);
    const SceneDescription description =
        test::four_part_sphere(two, assets->mesh, test::scratch_dir() + "/four_part_sphere_labels.txt");
    const int size = 256;
    const RunConfig config = test::small_part_config(66, 60);  // tactile guidance at iterations 61-65
    const PartTraining parts =
        prepare_part_training(description, assets->mesh, assets->material, size, config.gutter, "four parts");
    const std::vector<int>& truth = parts.segmentation.texel_part;  // face_labels: the ground truth
    const TrainingTarget target = test::part_target(*assets, parts);
    Trainer trainer(target, config, 3);
    trainer.set_guidance(nullptr, nullptr);
    while (trainer.iteration() < config.init_iterations) trainer.step();

    // The 4-logit head learns the parts.
    const std::vector<int> predicted = trainer.predicted_texel_parts();
    std::size_t right = 0, labelled = 0;
    for (std::size_t t = 0; t < truth.size(); ++t)
        if (truth[t] >= 0) ++labelled, right += predicted[t] == truth[t];
    const double accuracy = double(right) / double(labelled);
    // Boundaries after matching: bleed and seam (README "Multi-part textures").
    const Image matched = trainer.export_maps().tactile_normal;
    const PartBoundaryMeasure m = measure_part_boundary(matched, truth, size, parts.layers);

    // Refinement from the same state three times: part 1 alone guided by TiltBackend, no
    // guidance at all, and every part by exemplar_patch_match with its own map as exemplar.
    const std::vector<float> parameters = trainer.parameters();
    const AdamState adam = trainer.optimizer_state();
    const auto refine = [&](const std::function<std::unique_ptr<GuidanceBackend>(int)>& backend_of,
                            LossRecord* last, float matching = -1) {
        trainer.restore(config.init_iterations, parameters, adam);
        std::vector<PartGuidance> gates(4);
        for (int k = 0; k < 4; ++k) {
            gates[std::size_t(k)].name = target.part_names[std::size_t(k)];
            gates[std::size_t(k)].backend = backend_of(k);
            gates[std::size_t(k)].settings.matching_weight = matching;
        }
        trainer.set_part_guidance(std::move(gates));
        LossRecord record;
        while (trainer.iteration() < config.iterations) record = trainer.step();
        if (last) *last = record;
        return trainer.export_maps().tactile_normal;
    };
    TiltBackend* tilt = nullptr;
    const auto tilt_part1 = [&](int k) -> std::unique_ptr<GuidanceBackend> {
        if (k != 1) return nullptr;
        auto b = std::make_unique<TiltBackend>();
        tilt = b.get();
        return b;
    };
    LossRecord tilted_record, exemplar_record;
    const Image tilted = refine(tilt_part1, &tilted_record);
    ASSERT_NE(tilt, nullptr);
    EXPECT_EQ(tilt->calls, 5);
    const Image unguided = refine([](int) { return nullptr; }, nullptr);
    // Without the matching terms nothing else moves the normal map: what changed is the tilt's.
    const Image tilted_alone = refine(tilt_part1, nullptr, 0.0f);
    const Image exemplar = refine(
        [&](int k) {
            auto b = GuidanceBackend::create("exemplar_patch_match", Json::object());
            b->set_exemplars({load_tactile_map(description.parts.parts[std::size_t(k)].tactile_images.front()).normals});
            return b;
        },
        &exemplar_record);

    // Gating: only part 1's pixels asked for the tilt, so the texels it moved are part 1's and
    // those sharing a lookup footprint with them (the refinement's bleed).
    // Alone, the guidance moves no other part's texel; with the matching terms, the other parts'
    // pixels that read a moved texel of part 1 pull their own texels next to it back on target.
    const std::vector<double> to_part1 = distance_to_part(truth, size, 1, 8);
    const auto reach_of = [&](const Image& after, const Image& before, double* part1_change) {
        double reach = 0, change_sum = 0;
        std::size_t part1_texels = 0;
        for (std::size_t t = 0; t < truth.size(); ++t) {
            if (truth[t] < 0) continue;
            const double change = angle_degrees(after, before, t);
            if (truth[t] == 1) {
                change_sum += change;
                ++part1_texels;
            } else if (change > 1.0) {
                reach = std::max(reach, to_part1[t]);
            }
        }
        *part1_change = change_sum / double(part1_texels);
        return reach;
    };
    double part1_change = 0, part1_change_alone = 0;
    const double reach = reach_of(tilted, unguided, &part1_change);
    const double reach_alone = reach_of(tilted_alone, matched, &part1_change_alone);
    const PartBoundaryMeasure e = measure_part_boundary(exemplar, truth, size, parts.layers);
    std::printf("four parts, %d texels: labels %.4f of %zu right; after matching bleed %.2f texels, step ratio %.2f, "
                "band detail %.3f; tilt guidance on part 1 moved its texels %.1f deg on average and others' up to "
                "%.2f texels away (alone: %.1f deg, %.2f texels); with per-part exemplar guidance step ratio %.2f, "
                "band detail %.3f\n",
                size, accuracy, labelled, m.bleed_texels, m.step_ratio, m.band_detail_ratio, part1_change, reach,
                part1_change_alone, reach_alone, e.step_ratio, e.band_detail_ratio);
    EXPECT_GE(accuracy, 0.98);
    EXPECT_LE(m.bleed_texels, 2.0);
    EXPECT_GT(m.boundary_pairs, 100u);
    EXPECT_LT(m.step_ratio, 0.7);
    EXPECT_NEAR(m.band_detail_ratio, 1.0, 0.1);
    EXPECT_GT(part1_change, 2.0);
    EXPECT_GT(part1_change_alone, 2.0);
    EXPECT_LE(reach, 2.0);
    EXPECT_EQ(reach_alone, 0.0);
    EXPECT_LT(e.step_ratio, 0.7);
    EXPECT_NEAR(e.band_detail_ratio, 1.0, 0.1);
    // Each part's own terms; only part 1 had guidance in the tilted run, every part in the other.
    for (int k = 0; k < 4; ++k) {
        const std::string name = target.part_names[std::size_t(k)];
        EXPECT_EQ(tilted_record.terms.count("tactile_matching_" + name), 1u) << name;
        EXPECT_EQ(tilted_record.terms.count("tactile_guidance_" + name), k == 1 ? 1u : 0u) << name;
        EXPECT_EQ(exemplar_record.terms.count("tactile_guidance_" + name), 1u) << name;
    }
}

TEST(TextureSpaceParts, LabelsFidelityAndBoundaryOnTheTwoPartSphere) {
    const SceneDescription description = load_scene(kFolder + "scene.json");
    const auto assets = load_scene_assets(description);
    const RunConfig config = test::small_part_config(60, 60);
    const PartTraining parts = prepare_part_training(description, assets->mesh, assets->material, 256,
                                                     config.gutter, "two_part_sphere: parts");
    const TrainingTarget target = test::part_target(*assets, parts);
    Trainer trainer(target, config, 3);
    trainer.set_guidance(nullptr, nullptr);
    ASSERT_TRUE(trainer.trains_labels());
    double first_label_loss = 0, last_label_loss = 0;
    while (trainer.iteration() < config.iterations) {
        const LossRecord r = trainer.step();
        if (r.iteration == 0) first_label_loss = r.terms.at("texture_label");
        last_label_loss = r.terms.at("texture_label");
    }
    EXPECT_LT(last_label_loss, 0.5 * first_label_loss);

    // Labels: the head's prediction against the ground truth (the mesh's per-face labels).
    PartsSpec truth_spec = description.parts;
    truth_spec.source.kind = "face_labels";
    truth_spec.source.file = kFolder + "labels.txt";
    truth_spec.parts[0].select = {"cap"};
    truth_spec.parts[1].select = {"base"};
    PartSegmentationInput in;
    in.mesh = in.atlas = &assets->mesh;
    in.material = &assets->material;
    in.size = 256;
    in.where = "truth";
    const PartSegmentation truth = segment_parts(truth_spec, in);
    const std::vector<int> predicted = trainer.predicted_texel_parts();
    ASSERT_EQ(predicted.size(), truth.texel_part.size());
    std::size_t right = 0, labelled = 0;
    for (std::size_t t = 0; t < predicted.size(); ++t)
        if (truth.texel_part[t] >= 0) ++labelled, right += predicted[t] == truth.texel_part[t];
    const double accuracy = double(right) / double(labelled);

    // Per-part fidelity: the learned normal map against each part's own laid map over its texels.
    const BakedMaps maps = trainer.export_maps();
    const int size = maps.tactile_normal.width();
    std::vector<double> cosine(2, 0.0);
    std::vector<std::size_t> count(2, 0);
    for (std::size_t t = 0; t < truth.texel_part.size(); ++t) {
        const int p = truth.texel_part[t];
        if (p < 0) continue;
        const float* a = maps.tactile_normal.data() + 3 * t;
        const float* b = parts.layers[std::size_t(p)].data() + 3 * t;
        const Vec3f na = safe_normalize(Vec3f{a[0], a[1], a[2]});
        const Vec3f nb = safe_normalize(Vec3f{b[0], b[1], b[2]});
        cosine[std::size_t(p)] += double(dot(na, nb));
        ++count[std::size_t(p)];
    }
    const PartBoundaryMeasure boundary =
        measure_part_boundary(maps.tactile_normal, truth.texel_part, size, parts.layers);
    std::printf("two_part_sphere, 256 texels, %d matching iterations: labels %.4f of %zu texels right, "
                "normal cosine cap %.4f base %.4f, bleed %.2f texels, step %.2f deg (hard cut %.2f)\n",
                config.init_iterations, accuracy, labelled, cosine[0] / double(count[0]),
                cosine[1] / double(count[1]), boundary.bleed_texels, boundary.boundary_step_degrees,
                boundary.hard_step_degrees);
    EXPECT_GE(accuracy, 0.98);
    EXPECT_GE(cosine[0] / double(count[0]), 0.98);
    EXPECT_GE(cosine[1] / double(count[1]), 0.98);
    EXPECT_LE(boundary.bleed_texels, 2.0);
    EXPECT_GT(boundary.boundary_pairs, 0u);
}

TEST(TextureSpaceParts, LabelHeadLearnsTheSpotPartsOnTheRealMesh) {
    // scenes/spot_parts: colour segmentation of the cow (K = 6, cluster 3 = dark patches); the
    // head's prediction against that segmentation (its training labels) and against the
    // independent rule of PartSegmentation.SpotPatchesFromColourOnTheRealMesh (L* < 36).
    TDF_REQUIRE_SHARED_DATA("meshes/spot/spot_triangulated.obj");
    const std::string scene = test::source_dir() + "/scenes/spot_parts/scene.json";
    const SceneDescription description = load_scene(scene);
    const auto assets = load_scene_assets(description);
    const RunConfig config = test::small_part_config(60, 60);
    const PartTraining parts =
        prepare_part_training(description, assets->mesh, assets->material, 256, config.gutter, scene + ": parts");
    const TrainingTarget target = test::part_target(*assets, parts);
    Trainer trainer(target, config, 3);
    trainer.set_guidance(nullptr, nullptr);
    while (trainer.iteration() < config.iterations) trainer.step();
    const std::vector<int> predicted = trainer.predicted_texel_parts();
    const std::vector<int>& seg = parts.segmentation.texel_part;
    const std::vector<int> dark = test::spot_dark_patches(assets->mesh, assets->material, 256);
    std::size_t right = 0, dark_right = 0, labelled = 0, dark_labelled = 0;
    for (std::size_t t = 0; t < seg.size(); ++t) {
        if (seg[t] >= 0) ++labelled, right += predicted[t] == seg[t];
        if (dark[t] >= 0 && predicted[t] >= 0) ++dark_labelled, dark_right += predicted[t] == dark[t];
    }
    const double accuracy = double(right) / double(labelled);
    const double truth_accuracy = double(dark_right) / double(dark_labelled);
    std::printf("spot_parts, 256 texels, 60 matching iterations: the head agrees with the segmentation on %.4f of %zu "
                "texels and with the L* < 36 rule on %.4f of %zu\n", accuracy, labelled, truth_accuracy, dark_labelled);
    EXPECT_GE(truth_accuracy, 0.98);
    EXPECT_GE(accuracy, 0.98);
    const PartBoundaryMeasure m = measure_part_boundary(trainer.export_maps().tactile_normal, seg, 256, parts.layers);
    EXPECT_LE(m.bleed_texels, 2.0);
}

TEST(TextureSpaceParts, PixelEvaluationWithPartsIsRefusedInOneLine) {
    const SceneDescription description = load_scene(kFolder + "scene.json");
    const auto assets = load_scene_assets(description);
    const RunConfig config = test::small_part_config(2, 1, "pixel");
    const PartTraining parts = prepare_part_training(description, assets->mesh, assets->material, 256,
                                                     config.gutter, "two_part_sphere: parts");
    const TrainingTarget target = test::part_target(*assets, parts);
    try {
        Trainer trainer(target, config, 3);
        FAIL() << "pixel evaluation with parts was accepted";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("field.evaluation=texture"), std::string::npos) << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
}

TEST(TextureSpaceParts, PartGuidanceSettingsAndTheirErrors) {
    const PartGuidanceSettings s = PartGuidanceSettings::from_json(
        Json{{"backend", "none"}, {"weight", 0.2}, {"matching_weight", 0.0}, {"strength", 0.5}, {"config", Json::object()}},
        "s.json: parts.list[1].guidance");
    EXPECT_EQ(s.backend, "none");
    EXPECT_FLOAT_EQ(s.guidance_weight, 0.2f);
    EXPECT_FLOAT_EQ(s.matching_weight, 0.0f);
    EXPECT_DOUBLE_EQ(s.strength, 0.5);
    EXPECT_TRUE(s.backend_config.is_object());
    const PartGuidanceSettings defaults = PartGuidanceSettings::from_json(Json::object(), "x");
    EXPECT_TRUE(defaults.backend.empty());
    EXPECT_LT(defaults.guidance_weight, 0.0f);  // the run's
    for (const Json& bad : {Json{{"wieght", 1}}, Json{{"weight", -1}}, Json{{"strength", 2}}, Json{{"config", 3}}}) {
        try {
            PartGuidanceSettings::from_json(bad, "s.json: parts.list[1].guidance");
            ADD_FAILURE() << bad.dump() << " was accepted";
        } catch (const Error& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find("parts.list[1].guidance"), std::string::npos) << message;
            EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        }
    }
}
