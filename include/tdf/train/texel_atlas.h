#pragma once
/// The texels of a UV atlas as surface samples: the texture-space optimizer's table (issue 10,
/// texture-space design). Built once per run from the mesh's UVs at the map size:
///  - every texel whose centre a UV triangle covers, plus the texels a chart only partly covers
///    (at the nearest point of the chart, add_partial_texels), with its surface point and UV;
///  - for every other texel (the gutter), the covered texel it copies, nearest ring first, so the
///    maps never blend background into bilinear or mip lookups and the gutter's adjoint is a
///    plain scatter back to that texel;
///  - the matching targets laid over the atlas: the base albedo and the tactile map sampled at
///    each texel's surface point with a footprint of one texel (trilinear), which is exactly what
///    the exported maps must reproduce after the matching phase.
#include <tdf/atlas/uv_raster.h>
#include <tdf/core/image.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/material_sampling.h>
#include <tdf/render/renderer.h>

#include <cstdint>
#include <vector>

namespace tdf {

struct TexelAtlas {
    int size = 0;
    UvRaster raster;                      ///< covered and partly covered texels (triangle >= 0)
    std::vector<std::uint32_t> texels;    ///< row-major indices of those texels, ascending
    std::vector<Vec3f> points;            ///< their surface points (world), same order
    std::vector<Vec2f> uvs;               ///< their UVs (OBJ convention), same order
    /// Per texel of the map: its index in `texels` when covered, else the index in `texels` of
    /// the covered texel it copies (-1 only for a map with no covered texel reachable).
    std::vector<int> source;

    std::size_t covered_count() const { return texels.size(); }
    std::size_t texel_count() const { return std::size_t(size) * std::size_t(size); }

    /// Builds the table for `mesh` (which must have UVs) at size x size texels.
    /// Throws tdf::Error when the mesh has no UVs or no texel is covered.
    static TexelAtlas build(const TriangleMesh& mesh, int size);

    /// Fills every gutter texel of `map` (size x size, any channels) from its source texel.
    void fill_gutter(Image& map) const;
    /// The adjoint of fill_gutter: adds each gutter texel's gradient to its source texel and
    /// zeroes it. Serial over texels (deterministic); cheap (one pass).
    void fold_gutter_gradient(Image& gradient) const;
    /// Frees what only laying the targets over the atlas reads (the raster's barycentrics and the
    /// texels' UVs: 20 bytes a texel, 0.3 GB at 4096^2), once they are laid; albedo_target(),
    /// tactile_target() and cross_fade_tactile_seams() refuse the atlas from then on.
    void release_target_inputs();
    bool has_target_inputs() const { return uvs.size() == texels.size() && !raster.barycentric.empty(); }
};

/// The base albedo over the atlas: the material's texture sampled trilinearly at each texel's UV
/// with a one-texel footprint (prefiltered when the texture is larger than the map), vertex
/// colours interpolated, or the constant; gutter filled. RGB, size x size.
Image albedo_target(const TexelAtlas& atlas, const SurfaceMaterial& material, const TriangleMesh& mesh);

/// The tactile map laid over the atlas as the renderer and trainer lay it (uv x
/// material.tactile_layout.uv_scale), sampled with a one-texel footprint and renormalised (spec 3.1
/// step 5); (0,0,1) without a map; gutter filled.
Image tactile_target(const TexelAtlas& atlas, const SurfaceMaterial& material);

/// The tactile map laid as above at one UV (OBJ convention) with the footprint (duv_dx, duv_dy)
/// in the atlas's UVs, renormalised; (0,0,1) without a map.
Vec3f sample_tactile_layout(const SurfaceMaterial& material, Vec2f uv, Vec2f duv_dx, Vec2f duv_dy);

}  // namespace tdf
