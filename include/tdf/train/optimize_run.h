#pragma once
/// `tdf optimize` as a library call: load the scene, train, checkpoint, export. Everything a
/// run writes goes under `output_dir` (docs/asset-formats.md lists the files).
#include <tdf/core/image.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/parts/part_segmentation.h>
#include <tdf/scene/scene_file.h>

#include <string>
#include <vector>

namespace tdf {

struct OptimizeOptions {
    std::string scene_path;
    std::vector<std::string> overrides;  ///< `key=value` scene overrides
    std::string output_dir;
    std::string name;                    ///< file prefix; default: the scene file's folder name
    bool resume = false;                 ///< continue from `<output_dir>/checkpoint.bin`
    /// Stop (with a checkpoint) once this many iterations are done, 0 = run to the end. For
    /// batch schedulers with time limits: run in slices, each continuing with `resume`.
    int stop_after = 0;
};

/// The object words of the guidance prompt ("<object> with <texture description> texture, ..."):
/// the scene's `object_name` as written; else the mesh file's stem split into lower-case words
/// ("WaterBottle.glb" -> "water bottle", "an_avocado_2_mesh.obj" -> "an avocado"), leaving out
/// digits and words that name the file rather than the object (mesh, model, scene, gltf,
/// triangulated, ...); else the input's one named node / OBJ object; else the mesh's folder
/// name (the reference, spec 1.1); else "object".
std::string object_name_for_prompt(const SceneDescription& description, const TriangleMesh& mesh);

/// What a multi-part scene gives the trainer (docs/multi-part-textures.md): the segmentation
/// at the map size, each part's tactile map laid over the whole atlas with its layout, and the
/// composed target (TrainingTarget), grown `gutter` texels into the empty atlas.
struct PartTraining {
    PartSegmentation segmentation;
    std::vector<Image> layers;  ///< lay_part_maps, one per part
    Image target;               ///< compose_part_target(segmentation.texel_part, size, layers, band, gutter)
};
/// Segments `mesh` (which has UVs: the trained atlas) into the scene's parts at `size` texels
/// and composes the target. Throws tdf::Error naming `where` on bad input.
PartTraining prepare_part_training(const SceneDescription& description, const TriangleMesh& mesh,
                                   const SurfaceMaterial& material, int size, int gutter, const std::string& where);

/// Runs the whole job; throws tdf::Error on bad input or a failed run (the last good
/// checkpoint stays on disk and the message says how to resume).
void run_optimize(const OptimizeOptions& options);

}  // namespace tdf
