#pragma once
// The independent ground truth of scenes/spot_parts (shared by the parts and train tests): an
// atlas texel of spot is a dark patch when its albedo is darker than L* = 36.
#include <tdf/atlas/uv_raster.h>
#include <tdf/parts/colour_segmentation.h>
#include <tdf/parts/part_segmentation.h>

#include <vector>

namespace tdf::test {

/// Per texel of a size x size raster of `mesh`'s UVs (centre-covered and partial texels): 1 for a
/// dark patch, 0 for the hide, -1 where no face touches the texel.
inline std::vector<int> spot_dark_patches(const TriangleMesh& mesh, const SurfaceMaterial& material, int size) {
    UvRaster raster = rasterize_uv(mesh, size);
    add_partial_texels(mesh, raster);
    std::vector<int> dark(raster.texel_count(), -1);
    for (std::size_t i = 0; i < dark.size(); ++i)
        if (raster.triangle[i] >= 0)
            dark[i] = srgb_to_lab(albedo_at(mesh, material, raster.triangle[i], raster.barycentric[i])).x < 36.f ? 1 : 0;
    return dark;
}

}  // namespace tdf::test
