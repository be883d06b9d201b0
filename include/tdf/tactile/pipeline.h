#pragma once
/// The tactile pipeline's steps on HeightMaps (spec 6.2-6.4), used by `tdf tactile` and
/// available to other modules:
///   load_height_input -> extract_patch -> quilt_height_maps -> normal_map_from_height.
#include <tdf/tactile/height_input.h>
#include <tdf/tactile/height_map.h>
#include <tdf/tactile/quilting.h>
#include <tdf/tactile/texture_optimization.h>

#include <string>
#include <vector>

namespace tdf {

enum class HighPass {
    /// FftBlock; for normal-map inputs a Gaussian at a quarter of the input's width (5.1 mm for
    /// a 240 px GelSight patch): it removes the slow drift of the integrated heights, which
    /// would make quilting match absolute levels, and keeps millimetre-sized features.
    Auto,
    FftBlock,  ///< the reference's spectral block (spec 6.2 step 2), `freq_threshold` bins
    Gaussian,  ///< Gaussian high-pass with a cut-off wavelength in mm
    None,
};

/// A step that is on, off, or decided by the kind of input (see each option).
enum class Toggle { Auto, On, Off };

/// Step 1 (spec 6.2). Defaults match the reference for captures and height maps; normal-map
/// inputs (already processed patches, like the paper's dataset) are filtered more gently by
/// default, since the reference's 5-bin high-pass flattens features a few millimetres wide.
struct PatchOptions {
    HighPass high_pass = HighPass::Auto;
    int freq_threshold = 5;        ///< FFT block half-size in frequency bins
    float cutoff_mm = 2.0f;        ///< Gaussian cut-off wavelength
    /// Bilateral filter after the high-pass. Auto: off for every input but captures; captures get
    /// the widest window (bilateral_diameter, then 2 px less, ...) that takes at most
    /// kSmoothingMaxTiltLoss of the contact region's detail tilt, or none.
    Toggle smooth = Toggle::Auto;
    int bilateral_diameter = 5;
    float sigma_color = 125.0f;     ///< mm, like the reference's value on heights in mm
    float sigma_space = 125.0f;     ///< pixels
    Toggle contact = Toggle::Auto;  ///< contact crop; Auto: on for raw captures (.npz/.npy) only
    float depth_threshold = 0.5f;   ///< mm, on the raw (possibly inverted) heights
    /// Output side in pixels after resampling; 0 = keep the crop; -1 (auto) = 256 for captures
    /// (the reference), keep the resolution of every other input.
    int size = -1;
};

/// Smoothing of a capture may take this share of its contact region's mean detail tilt
/// (material_statistics), the material limits' tolerance. The reference's 5 px window (nearly a
/// box filter with its sigmas) takes 12 % of the strawberry's, but 30 % of the tilt of knit
/// loops 10 px apart: there it removes the texture, not the sensor's noise (issue 28).
constexpr double kSmoothingMaxTiltLoss = 0.15;

/// Intermediate images of step 1 for the step figures (empty when a step is skipped).
struct PatchSteps {
    Image raw, contact_mask, high_passed, smoothed, patch;
    /// The bilateral window used (0 = no smoothing), and the share of the detail tilt the
    /// reference's window (PatchOptions::bilateral_diameter) would have taken when auto
    /// smoothing chose a narrower one (else 0).
    int bilateral_diameter = 0;
    double full_window_tilt_loss = 0;
    /// The input's textured region (1 channel, the input's size): the contact mask of a
    /// capture, else texture_region of the input's detail tilt.
    Image region;
    /// The input's normals at the amplitude its patch gets at strength 1 (for statistics).
    Image input_normals;
};

/// Step 1: finds the textured region, high-pass, smoothing, contact crop (captures; other
/// inputs keep their whole extent), resampling. The result is in mm (or pixel widths, see
/// HeightMap::pixel_heights) with minimum 0; mm_per_pixel follows the resampling;
/// texture_mask is the region inside the patch. reference_scale_mm is the crop's height range
/// (spec 6.2 step 6) for captures (.npz/.npy), else 0 (physical amplitude); captures also get
/// reference_mm_per_pixel, the capture's pixel size. Throws tdf::Error
/// (naming the input) for an empty contact mask or a flat patch (range <= 1e-6 mm).
HeightMap extract_patch(const HeightInput& input, const PatchOptions& options, PatchSteps* steps = nullptr);

/// Step 2: quilts height maps (mm, equal mm_per_pixel within 1%) into one, drawing blocks from
/// their texture masks; keeps their pixel size and the largest reference_scale_mm; the result
/// is tileable when the options are. `seams` (optional) receives QuiltResult::seams. Throws
/// tdf::Error naming mismatching inputs.
HeightMap quilt_height_maps(const std::vector<HeightMap>& patches, const QuiltOptions& options,
                            QuiltStats* stats = nullptr, Image* seams = nullptr);

/// Step 2b: texture optimisation (optimize_texture) of a synthesised map, e.g. the quilt of
/// `patches`, towards their textured regions (texture masks). Keeps the map's size, pixel size
/// and metadata; `options.tileable` follows the map.
HeightMap optimize_height_maps(const std::vector<HeightMap>& patches, const HeightMap& initial,
                               TextureOptimizationOptions options);

enum class Amplitude {
    Auto,       ///< Reference when the map has a reference_scale_mm, else Physical
    /// spec 6.4 step 3: slopes = height_mm * k(scale) per pixel of the capture
    /// (HeightMap::reference_mm_per_pixel; per pixel of the map when that is 0). The reference
    /// counts per pixel of its resampled 256 px patch, which lost slopes wherever the contact
    /// crop was smaller (issue 28).
    Reference,
    Physical,   ///< slopes = height_mm / mm_per_pixel: the true surface at its real size
};

/// Step 3: decoded normals (3 channels, OpenGL) of a height map; `strength` multiplies the
/// slopes on top of the amplitude rule. Physical amplitude takes heights in pixel widths when
/// HeightMap::pixel_heights, and 1 mm per pixel when the pixel size is unknown (then the
/// slopes are not known: see auto_strength). Tileable maps get periodic differences.
Image normal_map_from_height(const HeightMap& map, Amplitude amplitude = Amplitude::Auto,
                             float strength = 1.0f);

/// True when the slopes of `map` under `amplitude` are known: the reference rule, heights in
/// pixel widths, or a known pixel size.
bool slopes_known(const HeightMap& map, Amplitude amplitude);

/// `--strength auto`: 1 when the slopes are known (slopes_known), however gentle they are: a
/// normal map keeps its slopes. Otherwise (a height image of unknown size, whose slopes have no
/// scale) the factor that makes the mean detail tilt (material_statistics) of the map's
/// textured region kAutoStrengthTilt degrees.
constexpr double kAutoStrengthTilt = 8.0;
float auto_strength(const HeightMap& map, Amplitude amplitude);

/// The input normals that the statistics of a map converted from `patch` at `strength` compare
/// with (`tdf tactile convert`'s report): the input's own (steps.input_normals) when the slopes
/// of `patch` are known, so that the tilt ratio is the output's over the input's own whatever
/// the strength; else (slopes of unknown scale, which have no amplitude of their own) the
/// input at the output's strength.
Image compared_input_normals(const PatchSteps& steps, const HeightMap& patch, Amplitude amplitude, float strength);

/// Writes decoded normals as a PNG (8 or 16 bits, reference encoding, spec 6.4 step 5) or,
/// for an .exr path, as float decoded normals; `mm_per_pixel` (when > 0) and `source` are
/// stored as metadata (tdf:mm_per_pixel, "unknown" when 0; tdf:source), plus `extra`.
void write_normal_map(const std::string& path, const Image& normals, float mm_per_pixel,
                      const std::string& source, int bits = 8, const ImageMetadata& extra = {});

/// A height map as a 16-bit grey PNG over its own range, with the range (tdf:height_min_mm,
/// tdf:height_max_mm) and the map's metadata: load_height_input reads it back in mm.
void write_height_preview_png(const std::string& path, const HeightMap& map);

/// A height map as a grey PNG scaled to its own range (for step figures).
void write_height_preview(const std::string& path, const Image& height);

}  // namespace tdf
