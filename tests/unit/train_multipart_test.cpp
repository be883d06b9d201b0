// Multi-part texturing in the texture-space optimizer (issue 14): on the shipped two-part sphere,
// the label head learns the parts, the learned normal map carries each part's own tactile map
// and neither material bleeds into the other beyond 2 texels.
#include <tdf/core/error.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/parts/part_target.h>
#include <tdf/render/scene_assets.h>
#include <tdf/scene/scene_file.h>
#include <tdf/train/optimize_run.h>
#include <tdf/train/trainer.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>

using namespace tdf;

namespace {

const std::string kFolder = test::source_dir() + "/scenes/two_part_sphere/";

RunConfig small_config(int iterations, int init_iterations, const std::string& evaluation = "texture") {
    const Json optimize = {{"iterations", iterations},   {"init_iterations", init_iterations},
                           {"resolution", 128},          {"patch_resolution", 64},
                           {"batch_size", 2},            {"patch_batch_size", 2},
                           {"patch_half_extent", 0.3},   {"held_out_views", 2},
                           {"held_out_patches", 2}};
    return RunConfig::from_json(optimize, Json(), Json({{"texture_size", 256}}), Json(), "test",
                                Json({{"evaluation", evaluation}}));
}

// The two-part sphere's scene with four parts: face_labels in four latitude bands (by the
// face centroid's y), the two tactile maps alternating at repeats 2, 3, 4 and 5.
SceneDescription four_part_description(const SceneDescription& two_parts, const TriangleMesh& mesh) {
    const std::string file = test::scratch_dir() + "/four_part_sphere_labels.txt";
    {
        std::ofstream out(file);
        const Bounds3 b = compute_bounds(mesh);
        for (const Vec3i& t : mesh.triangles) {
            const float y = (mesh.positions[std::size_t(t.x)].y + mesh.positions[std::size_t(t.y)].y +
                             mesh.positions[std::size_t(t.z)].y) / 3.0f;
            const int band = std::clamp(int(4.0f * (y - b.lower.y) / (b.upper.y - b.lower.y)), 0, 3) * 0 + int(4 * (&t - mesh.triangles.data()) / std::ptrdiff_t(mesh.triangles.size()));
            out << "band" << band << "\n";
        }
    }
    SceneDescription d = two_parts;
    d.parts.source = PartsSourceSpec{};
    d.parts.source.kind = "face_labels";
    d.parts.source.file = file;
    d.parts.parts.clear();
    for (int k = 0; k < 4; ++k) {
        PartSpec p = two_parts.parts.parts[std::size_t(k % 2)];
        p.name = "band" + std::to_string(k);
        p.select = {p.name};
        p.layout.repeat = float(2 + k);
        d.parts.parts.push_back(p);
    }
    return d;
}

}  // namespace

TEST(TextureSpaceParts, FourPartProbe) {
    const SceneDescription two = load_scene(kFolder + "scene.json");
    const auto assets = load_scene_assets(two);
    const SceneDescription description = four_part_description(two, assets->mesh);
    for (int size : {256, 512}) {
        const PartTraining parts = prepare_part_training(description, assets->mesh, assets->material, size, 8, "four");
        const PartBoundaryMeasure m = measure_part_boundary(parts.target, parts.segmentation.texel_part, size, parts.layers);
        std::printf("size %d: bleed %.2f step %.2f hard %.2f detail %.3f pairs %zu\n", size, m.bleed_texels,
                    m.boundary_step_degrees, m.hard_step_degrees, m.band_detail_ratio, m.boundary_pairs);
        {
            const Image undilated = compose_part_target(parts.segmentation.texel_part, size, parts.layers);
            const PartBoundaryMeasure u = measure_part_boundary(undilated, parts.segmentation.texel_part, size, parts.layers);
            std::printf("  undilated compose: bleed %.2f step %.2f\n", u.bleed_texels, u.boundary_step_degrees);
        }
        RunConfig config = small_config(3, 2);
        config.texture_size = size;
        TrainingTarget target;
        target.mesh = &assets->mesh;
        target.scene = assets->scene.get();
        target.material = &assets->material;
        target.tactile_target_override = &parts.target;
        target.texel_parts = &parts.segmentation.texel_part;
        target.part_names = parts.segmentation.part_names;
        Trainer trainer(target, config, 3);
        trainer.set_guidance(nullptr, nullptr);
        trainer.step();
        trainer.step();
        const BakedMaps maps = trainer.export_maps();
        const PartBoundaryMeasure l = measure_part_boundary(maps.tactile_normal, parts.segmentation.texel_part, size, parts.layers);
        std::printf("  learned: bleed %.2f step %.2f\n", l.bleed_texels, l.boundary_step_degrees);
        const PartBoundaryMeasure t2 = measure_part_boundary(trainer.tactile_target(), parts.segmentation.texel_part, size, parts.layers);
        std::printf("  trainer target: bleed %.2f step %.2f\n", t2.bleed_texels, t2.boundary_step_degrees);
        const LossRecord r = trainer.step();
        for (const auto& [k, v] : r.terms) std::printf("  %s %.4f\n", k.c_str(), v);
    }
}

TEST(TextureSpaceParts, LabelsFidelityAndBoundaryOnTheTwoPartSphere) {
    const SceneDescription description = load_scene(kFolder + "scene.json");
    const auto assets = load_scene_assets(description);
    const RunConfig config = small_config(60, 60);
    const PartTraining parts = prepare_part_training(description, assets->mesh, assets->material, 256,
                                                     config.gutter, "two_part_sphere: parts");
    TrainingTarget target;
    target.mesh = &assets->mesh;
    target.scene = assets->scene.get();
    target.material = &assets->material;
    target.tactile_target_override = &parts.target;
    target.texel_parts = &parts.segmentation.texel_part;
    target.part_names = parts.segmentation.part_names;
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

TEST(TextureSpaceParts, PixelEvaluationWithPartsIsRefusedInOneLine) {
    const SceneDescription description = load_scene(kFolder + "scene.json");
    const auto assets = load_scene_assets(description);
    const RunConfig config = small_config(2, 1, "pixel");
    const PartTraining parts = prepare_part_training(description, assets->mesh, assets->material, 256,
                                                     config.gutter, "two_part_sphere: parts");
    TrainingTarget target;
    target.mesh = &assets->mesh;
    target.scene = assets->scene.get();
    target.material = &assets->material;
    target.tactile_target_override = &parts.target;
    target.texel_parts = &parts.segmentation.texel_part;
    target.part_names = parts.segmentation.part_names;
    try {
        Trainer trainer(target, config, 3);
        FAIL() << "pixel evaluation with parts was accepted";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("field.evaluation=texture"), std::string::npos) << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
}
