#include <tdf/train/asset_height.h>

#include <tdf/core/log.h>
#include <tdf/render/material_sampling.h>
#include <tdf/tactile/height_map.h>
#include <tdf/tactile/tactile_map.h>

#include <cmath>

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

}  // namespace tdf
