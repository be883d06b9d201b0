#pragma once
// What run_optimize gives the trainer for a multi-part scene (shared by the multi-part tests).
#include <tdf/render/scene_assets.h>
#include <tdf/train/optimize_run.h>
#include <tdf/train/trainer.h>

#include <string>

namespace tdf::test {

/// A small texture-space run (256^2 atlas, 128 px views, 64 px patches, 2 + 2 per iteration).
inline RunConfig small_part_config(int iterations, int init_iterations, const std::string& evaluation = "texture") {
    const Json optimize = {{"iterations", iterations},   {"init_iterations", init_iterations},
                           {"resolution", 128},          {"patch_resolution", 64},
                           {"batch_size", 2},            {"patch_batch_size", 2},
                           {"patch_half_extent", 0.3},   {"held_out_views", 2},
                           {"held_out_patches", 2}};
    return RunConfig::from_json(optimize, Json(), Json({{"texture_size", 256}}), Json(), "test",
                                Json({{"evaluation", evaluation}}));
}

inline TrainingTarget part_target(const SceneAssets& assets, const PartTraining& parts) {
    TrainingTarget target;
    target.mesh = &assets.mesh;
    target.scene = assets.scene.get();
    target.material = &assets.material;
    target.tactile_target_override = &parts.target;
    target.texel_parts = &parts.segmentation.texel_part;
    target.part_names = parts.segmentation.part_names;
    return target;
}

}  // namespace tdf::test
