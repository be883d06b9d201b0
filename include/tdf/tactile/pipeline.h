#pragma once
/// The tactile pipeline's steps on HeightMaps (spec 6.2-6.4), used by `tdf tactile` and
/// available to other modules:
///   load_height_input -> extract_patch -> quilt_height_maps -> normal_map_from_height.
#include <tdf/tactile/height_input.h>
#include <tdf/tactile/height_map.h>
#include <tdf/tactile/quilting.h>

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
    Toggle smooth = Toggle::Auto;  ///< bilateral filter after the high-pass; Auto: off for normal maps
    int bilateral_diameter = 5;
    float sigma_color = 125.0f;     ///< mm, like the reference's value on heights in mm
    float sigma_space = 125.0f;     ///< pixels
    Toggle contact = Toggle::Auto;  ///< contact crop; Auto: on for raw captures (.npz/.npy) only
    float depth_threshold = 0.5f;   ///< mm, on the raw (possibly inverted) heights
    int size = 256;                 ///< output side in pixels after resampling; 0 = keep the crop
};

/// Intermediate images of step 1 for the step figures (empty when a step is skipped).
struct PatchSteps {
    Image raw, contact_mask, high_passed, smoothed, patch;
};

/// Step 1: high-pass, smoothing, contact crop (a centred square when the crop is off),
/// resampling. The result is in mm with minimum 0; mm_per_pixel follows the resampling and
/// reference_scale_mm is the crop's height range (spec 6.2 step 6), except for integrated
/// normal maps, whose slopes are already true (0: physical amplitude). Throws tdf::Error
/// (naming the input) for an empty contact mask or a flat patch (range <= 1e-6 mm).
HeightMap extract_patch(const HeightInput& input, const PatchOptions& options, PatchSteps* steps = nullptr);

/// Step 2: quilts height maps (mm, equal mm_per_pixel within 1%) into one; keeps their pixel
/// size and the largest reference_scale_mm. Throws tdf::Error naming mismatching inputs.
HeightMap quilt_height_maps(const std::vector<HeightMap>& patches, const QuiltOptions& options,
                            QuiltStats* stats = nullptr);

enum class Amplitude {
    Auto,       ///< Reference when the map has a reference_scale_mm, else Physical
    Reference,  ///< spec 6.4 step 3: slopes = height_mm * k(scale) per pixel
    Physical,   ///< slopes = height_mm / mm_per_pixel: the true surface at its real size
};

/// Step 3: decoded normals (3 channels, OpenGL) of a height map; `strength` multiplies the
/// slopes on top of the amplitude rule.
Image normal_map_from_height(const HeightMap& map, Amplitude amplitude = Amplitude::Auto,
                             float strength = 1.0f);

/// Writes decoded normals as a PNG (8 or 16 bits, reference encoding, spec 6.4 step 5) or,
/// for an .exr path, as float decoded normals; `mm_per_pixel` (when > 0) and `source` are
/// stored as metadata (tdf:mm_per_pixel, tdf:source).
void write_normal_map(const std::string& path, const Image& normals, float mm_per_pixel,
                      const std::string& source, int bits = 8);

/// A height map as a grey PNG scaled to its own range (for step figures).
void write_height_preview(const std::string& path, const Image& height);

}  // namespace tdf
