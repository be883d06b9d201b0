#pragma once
/// The composed tactile target of a multi-part scene, in texture space: every atlas texel takes
/// the tactile normal of its part's map laid with that part's layout; across a part boundary the
/// two maps are cross-faded over the texels touching it only (no material reaches more than
/// sqrt 2 texels into the other with the default band), spreading the jump between the two
/// textures over those texels and keeping the relief's strength there (measure_part_boundary).
/// Also the per-part masks and the label map exports.
#include <tdf/core/config.h>
#include <tdf/core/image.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/texture.h>
#include <tdf/scene/scene_file.h>

#include <string>
#include <vector>

namespace tdf {

/// One part's tactile map and its layout: tangent-space unit normals in [-1, 1] (decoded), laid
/// at uv' = uv * uv_scale with wrap-around (1 = covers the atlas once; see PartLayoutSpec and
/// physical_tactile_uv_scale for the physical layout).
struct PartTactile {
    const MipTexture* map = nullptr;
    float uv_scale = 1.f;
};

/// Each part's map laid over the WHOLE size x size atlas (bilinear at texel centres, v up, the
/// UvRaster convention), ignoring labels: the layers compose_part_target selects from.
std::vector<Image> lay_part_maps(const std::vector<PartTactile>& parts, int size);

/// The parts of a scene laid over an atlas: each part's first tactile map at its layout's scale
/// (`repeat`, or for `physical` physical_tactile_uv_scale with the part's mm_per_pixel or the map's
/// own metadata) and the layers lay_part_maps makes of them.
struct ScenePartMaps {
    std::vector<float> uv_scales;  ///< per part
    std::vector<Image> layers;     ///< per part, size x size
};

/// Loads every part's tactile map and lays it over `atlas`'s UVs at size x size. Throws
/// tdf::Error naming `where` and the part when a physical layout has no millimetres per pixel.
ScenePartMaps lay_scene_part_maps(const PartsSpec& spec, const TriangleMesh& atlas, int size,
                                  const std::string& where);

/// Blend band, in texels: a texel at centre distance d from the nearest texel of another part
/// keeps weight min(1, 0.5 + 0.5 (d - 0.5) / band) for its own part (the rest goes to that
/// part, blended by blend_normals). With the default 1.5 the texels touching the boundary
/// (d = 1: 0.67, d = sqrt 2: 0.80) are blended and every texel at d >= 2 is pure, so neither
/// material reaches more than sqrt 2 texels into the other; band 1 blends the same texels less.
constexpr float kDefaultPartBand = 1.5f;

/// The composed target normal map (3 channels, unit normals in [-1, 1]) from per-texel labels
/// of the surface (index i * size + j; -1 = no face covers the texel) and the layers of
/// lay_part_maps. `band` in [0, 4]; 0 = hard cut. The blend looks only at surface texels; then
/// the target grows `gutter` texels into the empty atlas (dilate_labels), each such texel taking
/// its grown part's layer unblended, so lookups near chart borders stay in their part; texels
/// left without a part are flat (0,0,1). Blending against labels already grown into the gutter
/// would let another chart's gutter pull a part's texels into the band: that made the 2.83-texel
/// bleed measured with 4 parts (docs/multi-part-textures.md).
Image compose_part_target(const std::vector<int>& labels, int size, const std::vector<Image>& layers,
                          float band = kDefaultPartBand, int gutter = 0);

/// Mip levels: the ordinary box-filtered pyramid of the composite (MipTexture) is what to use.
/// A coarse texel then mixes two parts only when its footprint at level 0 holds texels of both
/// or of the blend band, in proportion to their areas, which is needed (the footprint does show
/// both materials); composing every level from per-part pyramids with a band of its own mixes
/// MORE (measured in PartTarget.BoxPyramidMixesPartsOnlyWhereTheFootprintHoldsBoth).

/// 2x2 majority of a label raster (ties: the lowest label; -1 only when all four are -1).
std::vector<int> downsample_labels(const std::vector<int>& labels, int size);

/// Labels grown `texels` rings into unlabelled (-1) texels, 8-neighbour, each new texel taking
/// the smallest label among its labelled neighbours: the gutter gets the part of the chart it
/// borders, so bilinear and mip lookups near chart borders stay in their part.
std::vector<int> dilate_labels(const std::vector<int>& labels, int size, int texels);

/// 1-channel mask, 1 where labels == part.
Image part_mask(const std::vector<int>& labels, int size, int part);

/// How compose_part_target handles the boundaries (docs/multi-part-textures.md).
struct PartBoundaryMeasure {
    /// Bleeding: the largest distance (texels, centre to centre) from the other part at which a
    /// texel's normal differs from its own part's layer by more than `tolerance_degrees`.
    double bleed_texels = 0;
    /// The same per part (over the texels of that part): which material strays, for the report.
    std::vector<double> part_bleed_texels;
    /// Mean angle (degrees) between 4-neighbour texels of different parts in the composite, and
    /// what a hard cut shows there (own layer against the neighbour's layer).
    double boundary_step_degrees = 0;
    double hard_step_degrees = 0;
    /// boundary_step / hard_step: 1 = a hard cut (a visible line where the two textures jump),
    /// about 0.5 = the jump is spread over the band texels.
    double step_ratio = 0;
    /// Mean slope (|(x, y)| / z) of the composite in the band texels over the mean of the two
    /// layers' slopes there: 1 = the detail keeps its strength; a linear blend of independent
    /// textures drops toward 0.7 (a flattened line, the other kind of seam).
    double band_detail_ratio = 1;
    /// Mean angle between 4-neighbour texels of one part at least 6 texels from another part:
    /// the texture's own variation, for scale.
    double interior_step_degrees = 0;
    std::size_t boundary_pairs = 0;
    std::size_t band_texels = 0;
};
PartBoundaryMeasure measure_part_boundary(const Image& composed, const std::vector<int>& labels, int size,
                                          const std::vector<Image>& layers, float band = kDefaultPartBand,
                                          double tolerance_degrees = 1.0);

/// The band blend of two unit normals with weight `w` for `a`: a variance-preserving blend of
/// their slopes, (w s_a + (1-w) s_b) / sqrt(w^2 + (1-w)^2), so the texture's relief keeps its
/// strength across the band (a plain average flattens it). w = 1 gives `a`, w = 0 gives `b`.
Vec3f blend_normals(Vec3f a, Vec3f b, float w);

/// Fixed colour of part `index` in label maps: red, green (the reference's part A / part B,
/// spec 7.4), blue, yellow, magenta, cyan, then golden-angle hues. sRGB in [0, 1].
Vec3f part_colour(int index);

/// Writes `<base>_label_map.png` (RGB8, one colour per part, gutter-dilated labels, black
/// background), `<base>_label_legend.json` (index, name, colour, texels, fraction) and
/// `<base>_mask_<name>.png` per part (8-bit grey, 255 inside). Atomic. Returns the legend.
Json write_part_maps(const std::string& base, const std::vector<int>& labels, int size,
                     const std::vector<std::string>& names, int gutter = 4);

}  // namespace tdf
