#pragma once
/// The physical scale of an optimize run's exported maps (issue 24): how many millimetres a
/// texel of the atlas and a unit of the mesh span, so that the height map written beside the
/// normal map is in mm and its displacement in mesh units.
#include <tdf/render/scene_assets.h>
#include <tdf/tactile/height_export.h>
#include <tdf/train/run_config.h>

namespace tdf {

/// The scene's tactile map lies sqrt(W x H) x uv_scale of its pixels on one UV unit; at its
/// pixel size (tactile_layout.mm_per_pixel, else the map's tdf:mm_per_pixel, else GelSight
/// Mini's 0.085 mm with `assumed` set) that is the UV unit's length in mm, spread over
/// config.texture_size texels. mm per mesh unit: tactile_layout.mm_per_unit in physical layout,
/// else that UV length over export_mesh's mean length per UV unit (mesh_units_per_uv_unit).
/// Multi-part scenes take the first tactile map's. Returns mm_per_texel 0 without a tactile map
/// or UVs (nothing to integrate).
ExportScale asset_export_scale(const SceneAssets& assets, const TriangleMesh& export_mesh, const RunConfig& config);

}  // namespace tdf
