#pragma once
/// The relief an exported tangent-space normal map stands for, as a height map at physical
/// scale (issue 24): what `tdf tactile convert` and `tdf optimize` write beside the normal map
/// (`<stem>_height.exr` in mm, `<stem>_height.png` 16-bit), and the check that the two agree.
///
/// The heights are integrated from the exported normals themselves (not from the height field the
/// normals were once made of: amplitude modes, strength and the optimizer change the slopes), with
/// the very difference operator normals_from_height applies, so that normals recomputed from the
/// written heights reproduce the written normal map.
#include <tdf/core/config.h>
#include <tdf/core/image.h>
#include <tdf/tactile/height_map.h>

#include <string>

namespace tdf {

/// Least-squares heights (1 channel, zero mean, in pixel widths) whose central-difference
/// normals (normals_from_height with gain 1) are closest to `normals` (3+ channels, decoded; nz
/// clamped to at least 0.1): Frankot-Chellappa with the central-difference operator
/// i sin(w) instead of i w, solved with one FFT. `periodic`: the map wraps (a tileable map);
/// else the solution is that of the map mirrored to twice its size (even heights, odd slopes),
/// so its borders do not wrap, computed with one DCT-II pair on the map itself (8 bytes a texel).
/// What central differences cannot see (the checkerboard at the Nyquist frequency) is left out
/// (zero). Throws tdf::Error naming `what` below 3 x 3 or for non-finite normals.
Image integrate_normal_map(const Image& normals, bool periodic, const std::string& what = "normal map");

/// Mean cosine between `normals` (3+ channels, decoded; the length does not count) and the
/// normals of `height_mm` at `mm_per_texel` (normals_from_height with gain 1 / mm_per_texel and
/// `periodic` wrapping), over the texels where `mask` (1 channel; empty = all) is non-zero.
double height_normal_consistency(const Image& height_mm, float mm_per_texel, const Image& normals, bool periodic,
                                 const Image& mask = Image());

/// A height map made for export, with the numbers a reader needs to restore millimetres.
struct ExportedHeight {
    HeightMap map;              ///< heights in mm (map.mm_per_pixel = mm per texel), zero mean
    float min_mm = 0, max_mm = 0;
    double mean_cosine = 0;     ///< height_normal_consistency against the normals it came from
    /// On a mesh (export_surface_height): the consistency at one texel size (mm_per_texel) and
    /// at each texel's own size on the surface, the number of texel pairs held level across UV
    /// seams, and the texel size the heights were integrated at ("map" or "surface"; mean_cosine
    /// is that one's). Else -1, -1, 0 and empty.
    double texture_space_cosine = -1, surface_cosine = -1;
    std::size_t seam_links = 0;
    std::string metric;
    /// "full" (heights_on_surface) or "chart_offsets" (level_chart_offsets: where full levelling
    /// would cost the normal map's consistency more than it gives); empty without a mesh.
    std::string seam_levelling;
    /// Ambient occlusion of the heights (ambient_occlusion.h), written as `<base>_ao.png` when
    /// set; empty = none.
    Image occlusion;
    bool assumed_pixel_size = false;  ///< mm per texel was not known: see ExportScale
    /// mm per step of the 16-bit PNG: (max - min) / 65535.
    double mm_per_step() const { return double(max_mm - min_mm) / 65535.0; }
};

/// How big a texel is, and a mesh unit, for an exported map.
struct ExportScale {
    float mm_per_texel = 0;      ///< lateral size of one texel of the exported maps, mm
    float mm_per_unit = 0;       ///< mm per mesh unit (0 = no mesh: a bare normal map)
    bool assumed = false;        ///< the capture's pixel size was unknown: GelSight Mini's taken
    bool periodic = false;       ///< the map tiles (tdf tactile convert), else an atlas
    /// The capture the relief came from: its pixel size (mm) and size in pixels, the sensor a
    /// virtual GelSight presses by default (`tdf tactile simulate`); 0 = unknown.
    float capture_mm_per_pixel = 0;
    int capture_width = 0, capture_height = 0;
};

/// The height of `normals` (decoded, as the written file decodes) at `scale`, with its
/// consistency measured over `mask` (empty = all texels).
ExportedHeight export_height(const Image& normals, const ExportScale& scale, const std::string& source,
                             const Image& mask = Image());

/// Writes `<base>_height.exr` (float, mm, tactile metadata) and `<base>_height.png` (16-bit,
/// (h - min) / (max - min), with tdf:height_min_mm / tdf:height_max_mm so that `tdf tactile`
/// reads it back in mm), and `<base>_ao.png` (8-bit) when height.occlusion is set. Atomically.
void write_exported_height(const std::string& base, const ExportedHeight& height);

/// The scale as JSON for reports, MTL comments and glTF extras: mm_per_texel, mm_per_unit,
/// min_mm, max_mm, mm_per_step (16-bit), the file names (`png`, `exr`, given), the consistency
/// cosine, and blender's displacement modifier settings (strength in mesh units per full PNG
/// step, midlevel) when mm_per_unit is known; `ambient_occlusion` (the PNG's name, the march's
/// radius and directions, the mean visibility) when height.occlusion is set.
Json exported_height_json(const ExportedHeight& height, const ExportScale& scale, const std::string& png_name,
                          const std::string& exr_name);

/// The consistency limit of issue 24: mean cosine at least this.
constexpr double kHeightConsistencyLimit = 0.995;

}  // namespace tdf
