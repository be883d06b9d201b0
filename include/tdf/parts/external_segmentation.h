#pragma once
/// The `external` parts source: a user program (e.g. a promptable segmenter) through a file
/// protocol like the guidance backends' (docs/parts-protocol.md, `tdf-parts/1`): tdf renders the
/// mesh's albedo from orbit views, the program writes one mask per part and view, and the masks
/// are projected back onto the faces (votes of the pixels each face covers, then neighbourhood
/// smoothing over face adjacency).
#include <tdf/core/config.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/renderer.h>

#include <string>
#include <vector>

namespace tdf {

struct ExternalSegmentationInput {
    const TriangleMesh* mesh = nullptr;  ///< normalised to about [-1, 1] (the views orbit at radius 3)
    const SurfaceMaterial* material = nullptr;
    std::vector<std::string> part_names;
    std::vector<std::string> prompts;  ///< per part, "" = the part's name
    std::string work_folder;           ///< parent of the call folder ("" = system temp)
    std::string where;                 ///< names the settings in messages
    int smoothing = 3;                 ///< rounds of face-adjacency majority smoothing
};

/// Runs the program once for all views and returns the part of every face. `config` keys
/// (docs/parts-protocol.md): command (required), shell, timeout_seconds (600), views (8),
/// resolution (512), elevations ([-20, 20]), radius (3), fovy (50), keep_files (false).
/// Throws tdf::Error naming `where` when the program fails, times out, or writes missing or
/// wrongly sized masks; faces no view sees take their neighbours' part.
std::vector<int> run_external_segmentation(const Json& config, const ExternalSegmentationInput& input);

}  // namespace tdf
