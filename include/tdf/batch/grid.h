#pragma once
/// `tdf batch grid`: the "every object with every material" manifest. One job per (scene or
/// mesh) x (tactile texture) x (override set), in that nesting order.
#include <tdf/batch/manifest.h>

#include <string>
#include <vector>

namespace tdf {

struct GridSpec {
    std::string command = "optimize";   ///< optimize or render
    std::vector<std::string> scenes;    ///< scene files (.json) or meshes (.obj, .gltf, .glb, .ply)
    std::string base_scene;             ///< the scene a mesh is placed in (`mesh=<path>`); needed for meshes
    std::vector<std::string> textures;  ///< tactile normal maps; none = the scenes' own
    std::vector<std::string> override_sets;  ///< each a shell-like list of key=value; none = one empty set
};

/// The jobs, named `<object>_<texture>[_<k>]` (object: the scene's folder name or the mesh's stem;
/// texture: the file's stem; k: the override set's index when there are several), made unique
/// and reduced to A-Z a-z 0-9 . _ -. Paths are made absolute, because a scene resolves
/// relative override paths against its own folder. Throws tdf::Error for a missing file, a
/// mesh without `base_scene`, or an unknown command.
std::vector<BatchJob> make_grid(const GridSpec& spec);

}  // namespace tdf
