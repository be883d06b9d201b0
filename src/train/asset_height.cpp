#include <tdf/train/asset_height.h>

#include <tdf/atlas/surface_height.h>
#include <tdf/core/log.h>
#include <tdf/tactile/ambient_occlusion.h>
#include <tdf/render/material_sampling.h>
#include <tdf/tactile/height_map.h>
#include <tdf/tactile/tactile_map.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace tdf {

ExportScale asset_export_scale(const SceneAssets& assets, const TriangleMesh& export_mesh, const RunConfig& config) {
    ExportScale scale;
    const SurfaceMaterial& m = assets.material;
    if (!m.tactile || m.tactile->empty() || !export_mesh.has_uvs() || assets.description.tactile_images.empty())
        return scale;
    float mm_per_pixel = config.tactile_mm_per_pixel;
    if (!(mm_per_pixel > 0)) mm_per_pixel = load_tactile_map(assets.description.tactile_images.front()).mm_per_pixel;
    if (!(mm_per_pixel > 0)) {
        // The texture samples of the paper are GelSight Mini captures: their pixel is the sensor's.
        mm_per_pixel = kGelSightMiniMmPerPixel;
        scale.assumed = true;
    }
    const double uv_mm = std::sqrt(double(m.tactile->width()) * double(m.tactile->height())) *
                         double(m.tactile_layout.uv_scale) * double(mm_per_pixel);
    scale.mm_per_texel = float(uv_mm / double(config.texture_size));
    scale.capture_mm_per_pixel = mm_per_pixel;
    scale.capture_width = m.tactile->width(), scale.capture_height = m.tactile->height();
    scale.mm_per_unit = config.tactile_layout == TactileLayout::Physical
                            ? config.mm_per_unit
                            : float(uv_mm / mesh_units_per_uv_unit(export_mesh));
    return scale;
}

namespace {

/// How much of the texture-space heights' consistency (mean cosine) seam levelling may cost
/// before the export falls back to per-chart offsets (measured 2026-12-03 on the shipped scenes:
/// 0.0008 or less on the spheres, bottle, torus, mug and spot_parts; 0.0028 on the avocado and
/// 0.0096 on the cow, whose ramps show).
constexpr double kLevellingCosineLoss = 0.001;

}  // namespace

ExportedHeight export_surface_height(const Image& normals, const ExportScale& scale, const TriangleMesh& mesh,
                                     const UvRaster& raster, HeightMetric metric, const std::string& source) {
    const bool map_sized = raster.size == normals.width() && raster.size == normals.height();
    Image mask;
    if (map_sized) {
        mask = Image(raster.size, raster.size, 1);
        for (std::size_t t = 0; t < raster.texel_count(); ++t) mask.data()[t] = raster.triangle[t] >= 0 ? 1.0f : 0.0f;
    }
    ExportedHeight out = export_height(normals, scale, source, mask);
    if (!(scale.mm_per_unit > 0) || !mesh.has_uvs() || !map_sized || raster.covered_count() == 0) {
        out.occlusion = ambient_occlusion(out.map.height, scale.mm_per_texel, false);
        return out;
    }
    const SurfaceTexels surface = surface_texels(mesh, raster);
    SurfaceHeightStats stats;
    const double texture_space_only = out.mean_cosine;
    const Image texture_mm = std::move(out.map.height);  // replaced below: no copy (64 MB at 4096^2)
    out.map.height = heights_on_surface(texture_mm, scale.mm_per_texel, surface, scale.mm_per_unit, metric, &stats);
    out.texture_space_cosine = height_normal_consistency(out.map.height, scale.mm_per_texel, normals, false, mask);
    out.seam_levelling = "full";
    // Levelling bends a chart's relief into ramps where the two sides of its seams disagree; on an
    // atlas of small charts whose textures do not continue across them (the cow's) those ramps
    // are steeper than the relief. Then the charts only move up or down as wholes.
    if (metric == HeightMetric::Map && out.texture_space_cosine < texture_space_only - kLevellingCosineLoss) {
        out.map.height = level_chart_offsets(texture_mm, surface);
        out.texture_space_cosine = height_normal_consistency(out.map.height, scale.mm_per_texel, normals, false, mask);
        out.seam_levelling = "chart_offsets";
    }
    const auto [lo, hi] = std::minmax_element(out.map.height.values().begin(), out.map.height.values().end());
    out.min_mm = *lo, out.max_mm = *hi;
    out.surface_cosine = surface_height_consistency(out.map.height, normals, surface, scale.mm_per_unit);
    out.mean_cosine = metric == HeightMetric::Map ? out.texture_space_cosine : out.surface_cosine;
    out.seam_links = surface.seam_links.size();
    out.metric = metric == HeightMetric::Map ? "map" : "surface";
    // Each chart shades only itself: the gutter and the neighbouring charts of the atlas are
    // not the relief around a texel.
    std::vector<int> chart(surface.node.size(), -1);
    for (std::size_t i = 0; i < surface.covered_count(); ++i) chart[surface.texels[i]] = surface.chart[i];
    out.occlusion = ambient_occlusion(out.map.height, scale.mm_per_texel, false, chart);
    log_verbose("{}: heights levelled on the surface ({} texel size, {}): {} texels, {} seam links, {} "
                "conjugate-gradient iterations, relative residual {:.3g}",
                source, out.metric, out.seam_levelling, surface.covered_count(), surface.seam_links.size(),
                stats.iterations, stats.relative_residual);
    return out;
}

}  // namespace tdf
