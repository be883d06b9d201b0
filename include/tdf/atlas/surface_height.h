#pragma once
/// The heights a tangent-space normal map stands for on its surface (issue 24): least squares
/// over the atlas's covered texels, where each texel's slopes are taken over its own size and
/// direction on the surface (SurfaceTexels::step) and texels across a UV seam are held level.
///
/// Why not the texture-space Frankot-Chellappa integration alone: it assumes every texel has
/// one size, so wherever the atlas stretches (a sphere's UVs are 1.37x longer along u than the
/// mean) the displaced relief gets the stretch's slopes instead of the normal map's, and each
/// chart's heights float on their own, leaving a step along every seam. Displacing the mesh by
/// these heights gives back the normal map's slopes, which is what a displacement modifier and
/// a virtual GelSight see.
#include <tdf/atlas/surface_texels.h>
#include <tdf/core/image.h>

namespace tdf {

/// Which size a texel's slopes are taken over:
/// - `Map`: every texel the map's own (texture_mm_per_texel): the texture-space heights keep
///   their differences and only the seams are levelled. Normals recomputed at that one texel
///   size reproduce the normal map (the check of issue 24); where the atlas stretches, the
///   displaced relief stretches with it.
/// - `Surface`: each texel its own size and direction on the mesh (SurfaceTexels::step), so the
///   displaced relief has the normal map's slopes where the atlas stretches. A normal map laid on
///   a stretched atlas has no height field that matches it everywhere (its slopes are not
///   integrable over the surface's lengths): least squares shares the difference out.
enum class HeightMetric { Map, Surface };

struct SurfaceHeightStats {
    int iterations = 0;            ///< fine conjugate-gradient iterations in all
    double relative_residual = 0;  ///< |b - A h| / |b| at the end (normal equations)
};

/// The heights of `texture_mm` (size x size, 1 channel, mm; integrated in texture space as if
/// every texel were `texture_mm_per_texel` wide, e.g. integrate_normal_map) moved onto the
/// surface: least squares over the covered texels, where each 4-neighbour difference within a
/// chart keeps the slopes the texture-space difference stands for, taken over the texel size
/// `metric` says (the surface step between the two texels at `mm_per_unit`, or the map's), and
/// texels across seams agree. With a uniform,
/// isometric atlas and no seams the input comes back. Keeping the texture-space differences
/// (rather than fitting the normals again) keeps their fine structure, which the
/// central-difference check of the normal map sees. Keeps the mean per connected piece, then
/// zero mean over the covered texels; the gutter is filled (dilate_gutter). Solved by
/// conjugate gradients with a coarse-grid correction (8 x 8 texel aggregates per chart);
/// deterministic on any thread count.
Image heights_on_surface(const Image& texture_mm, float texture_mm_per_texel, const SurfaceTexels& surface,
                         float mm_per_unit, HeightMetric metric, SurfaceHeightStats* stats = nullptr);

/// Mean cosine, over the covered texels, between `normals` and the normals recomputed from
/// `height_mm` by central differences over each texel's surface step (one-sided where a
/// neighbour is outside the texel's chart): the check of issue 24 at the texel's own size.
double surface_height_consistency(const Image& height_mm, const Image& normals, const SurfaceTexels& surface,
                                  float mm_per_unit);

}  // namespace tdf
