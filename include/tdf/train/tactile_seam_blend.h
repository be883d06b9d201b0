#pragma once
/// The tactile map laid over an atlas repeats per chart, so where two charts meet (a seam that is
/// not a whole number of the map's periods, or charts turned against each other) the relief
/// breaks off: the learned normal map, which reproduces that layout, would show every seam.
/// `cross_fade_tactile_seams` blends, within `band_texels` of each seam, the texel's own relief
/// with the relief the chart on the other side lays at the same surface point (its layout
/// continued across the seam by the similarity that maps the seam edge's UVs on this side to the
/// other side's), turned from that chart's tangent frame into this one's. The weight of the other
/// side falls from 1/2 on the seam to 0 at `band_texels`, so both sides hold the same relief on
/// the seam and their own a band away. Charts whose layouts continue (a sphere's u = 0/1 seam with
/// a periodic map) are unchanged: the other side lays the same relief there.
#include <tdf/core/image.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/renderer.h>
#include <tdf/train/texel_atlas.h>

namespace tdf {

struct SeamBlendStats {
    std::size_t seam_edges = 0;      ///< Seam edges of the mesh (uv_seams.h)
    std::size_t blended_texels = 0;  ///< covered texels within the band of a seam
};

/// Blends `target` (the tactile map laid over `atlas`, tangent space, size x size RGB) across
/// the seams of `mesh` as described above, then refills the gutter. `band_texels` <= 0 leaves it
/// unchanged. Deterministic: every texel takes its nearest seam edge (ties: the first in
/// shared_edges order).
SeamBlendStats cross_fade_tactile_seams(Image& target, const TexelAtlas& atlas, const TriangleMesh& mesh,
                                        const SurfaceMaterial& material, float band_texels);

}  // namespace tdf
