#pragma once
/// `tdf optimize` as a library call: load the scene, train, checkpoint, export. Everything a
/// run writes goes under `output_dir` (README "tdf optimize" lists the files).
#include <tdf/mesh/triangle_mesh.h>
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

/// Runs the whole job; throws tdf::Error on bad input or a failed run (the last good
/// checkpoint stays on disk and the message says how to resume).
void run_optimize(const OptimizeOptions& options);

}  // namespace tdf
