#pragma once
/// The physical scale of an optimize run's exported maps (issue 24): how many millimetres a
/// texel of the atlas and a unit of the mesh span, so that the height map written beside the
/// normal map is in mm and its displacement in mesh units.
#include <tdf/atlas/surface_height.h>
#include <tdf/atlas/uv_raster.h>
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

/// The relief of an atlas's normal map on its mesh: export_height's texture-space integration
/// (one texel size) as the start, then heights_on_surface over `raster`'s covered texels with
/// `metric`, so that the charts' heights meet level at the seams (and, with
/// HeightMetric::Surface, each texel's slopes are taken over its own size on the mesh).
/// mean_cosine is the check at the metric's texel size; texture_space_cosine and surface_cosine
/// both are reported. Without mm_per_unit, or when the raster is not the map's size, the
/// texture-space heights alone.
ExportedHeight export_surface_height(const Image& normals, const ExportScale& scale, const TriangleMesh& mesh,
                                     const UvRaster& raster, HeightMetric metric, const std::string& source);

}  // namespace tdf
