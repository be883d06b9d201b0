#pragma once
/// Diffusion guidance behind an interface (spec 5.4-5.5).
///
/// In the reference the last 50 iterations refine the textures with two diffusion priors: a
/// normal-conditioned ControlNet refines the shaded colour renders (visual guidance) and a
/// per-texture TextureDreambooth LoRA refines the tactile patch normals (tactile guidance).
/// Both are "image in, refined image out" operations whose output the optimizer then uses as a
/// fixed target. A GuidanceBackend is exactly that operation; the optimizer turns the refined
/// targets into losses itself (visual: L1 plus a structural SSIM term standing in for LPIPS,
/// which needs VGG weights; tactile: 1 - cos as in the paper or MSE as in the reference code).
///
/// Backends (GuidanceBackend::create):
///  - "none": no guidance; create() returns nullptr and the optimizer skips the guidance terms.
///  - "exemplar_patch_match" (tactile, weight-free): rebuilds each patch from the nearest
///    patches of the touched tactile exemplars (tdf/guidance/exemplar_patch_match.h).
///  - "relief_shading" (visual, weight-free): darkens cavities and lightens ridges of the shaded
///    render following the curvature of the normal control image (tdf/guidance/relief_shading.h).
///  - "external": runs a user's program (stable-diffusion.cpp, a diffusers script, ...) per
///    call over a documented file protocol (tdf/guidance/external_backend.h,
///    docs/guidance-protocol.md).
/// No backend pretends to be a diffusion model: the built-ins do what their names say.
#include <tdf/core/config.h>
#include <tdf/core/image.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace tdf {

/// Which prior a request is for.
enum class GuidanceKind {
    Visual,   ///< colour renders conditioned on view-space normals (ControlNet, spec 5.4)
    Tactile,  ///< view-space normals of tactile patches (TextureDreambooth, spec 5.5)
};

/// "visual" or "tactile" (the names used in configs and in the external protocol).
const char* guidance_kind_name(GuidanceKind kind);
/// Parses "visual" / "tactile"; throws tdf::Error naming `where` otherwise.
GuidanceKind parse_guidance_kind(const std::string& text, const std::string& where);

/// One guidance call: a batch of N rendered images with their conditions.
struct GuidanceRequest {
    GuidanceKind kind = GuidanceKind::Visual;
    /// N images, all of one size.
    ///  - Visual: the shaded colour renders (`rendered_lambertians`), RGB in [0, 1],
    ///    composited on white.
    ///  - Tactile: the patch view-space shading normals (`rendered_perturb_normals`), 3 channels
    ///    in [-1, 1], zero vectors where the patch is empty (spec 5.3). Camera-space convention:
    ///    x right, y up, z toward the viewer (spec 3.5); rows as the renderer produced them
    ///    (the reference's patch renders are vertically flipped, spec 13.13).
    std::vector<Image> images;
    /// Visual only (empty for tactile): N control images, the view-space normals converted to
    /// the BAE convention with to_bae_control() (3 channels in [0, 1], background
    /// (0.5, 0.5, 1)).
    std::vector<Image> control;
    /// N coverage masks, 1 channel in [0, 1]; 0 = background (spec 3.6 antialiased coverage).
    std::vector<Image> masks;
    /// Optional (empty = unknown; tdf's optimizer fills them): the surface under the relief at
    /// every pixel, in the images' view space (visual requests: `surface_normals` only, so a
    /// backend can tell the relief's curvature from the mesh's). `surface_normals`: N images of the
    /// interpolated geometric normal (3 channels, unit, zero on the background);
    /// `surface_tangents`: N images of the unit tangent (dP/du) in channels 0-2 and the chart's
    /// handedness (+1 / -1, core/tangent_frame.h) in channel 3. With them a backend can separate
    /// the tactile detail from the surface's curvature and knows how the tactile map is turned
    /// (and whether it is mirrored) in each patch.
    std::vector<Image> surface_normals;
    std::vector<Image> surface_tangents;
    /// Visual only, optional (empty = unknown; tdf's optimizer fills them): N renders of the INPUT
    /// asset (its base albedo) under the same camera, light and relief as `images`, RGB in [0, 1]
    /// on white. A refinement that should keep the input's appearance (faces, prints, logos) and
    /// only add to it anchors on these instead of on the current render.
    std::vector<Image> reference_images;
    /// Tactile only: how many image pixels one texel of the tactile map spans on the surface in
    /// these renders (the patch window against the map's texel size on the atlas, a mean over
    /// the mesh); 0 = unknown. The reference's 0.15-unit, 512-pixel patches magnify a
    /// 1024-texel map over a unit-size atlas ~3.3x, a 256-texel one ~13x.
    float pixels_per_texel = 0.0f;
    /// Text conditions (spec 5.7; tactile guidance in the reference uses "sks normal map" / "").
    std::string prompt;
    std::string negative_prompt;
    /// Schedule value in the REFERENCE's semantics (spec 5.4, 13.21): the DDIM start index is
    /// `int(50 * strength)` of the 50-step schedule 981, 961, ..., 1, so LARGER strength means
    /// LESS noise and a target closer to the input. Visual: 0.5 -> 0.7 over the refinement
    /// (visual_guidance_strength()); tactile: constant 0.8 (kTactileGuidanceStrength).
    /// denoise_fraction() converts it to the usual img2img "strength" (fraction of the schedule
    /// that is denoised, diffusers and stable-diffusion.cpp semantics). Double precision on
    /// purpose: the floor in int(50 * strength) must see the reference's double value (a float
    /// turns 0.52 into 0.51999998 and starts one step earlier, spec 13.21).
    double strength = 0.5;
    /// Loop index i of the optimization (0-based, spec 5.1), for logging and file names.
    int iteration = 0;
    /// Seed for any random draw the backend makes (noise, search initialisation).
    std::uint64_t seed = 0;
};

/// The backend's answer: N refined target images, each the size of its input.
///  - Visual: RGB in [0, 1]; pixels whose mask is exactly 0 are white (spec 5.4).
///  - Tactile: 3 channels in [-1, 1], view-space normals in the input's convention.
struct GuidanceResult {
    std::vector<Image> refined;
};

/// Checks the request's shapes: N >= 1 images of one size with the channel counts documented
/// above, N masks of that size with 1 channel, N controls for visual requests (none for tactile),
/// surface frames either absent or N of each (tactile only), reference images either absent or N
/// of the images' shape (visual only), finite values, strength in [0, 1],
/// pixels_per_texel finite and >= 0. Throws tdf::Error naming `where` and the image index.
void validate_request(const GuidanceRequest& request, const std::string& where);

/// Checks a result against its request: N images, each of the input's size and channel count,
/// finite values. Throws tdf::Error naming `where` (e.g. the backend or the file).
void validate_result(const GuidanceRequest& request, const GuidanceResult& result, const std::string& where);

/// Converts view-space normals (3 channels, OpenGL camera convention x right, y up, z toward the
/// viewer, [-1, 1]) to the control image of the normal-BAE ControlNet.
/// Matches reference `convert_normal2bae` (spec 5.4): pixels whose three channels are exactly 0
/// become (0, 0, 1); x is negated (BAE: red = left, green = up, blue = toward the viewer); the
/// vector is normalized (torch F.normalize, eps 1e-12); the result is (n + 1) / 2 in [0, 1].
/// The background therefore becomes (0.5, 0.5, 1.0).
Image to_bae_control(const Image& viewspace_normals);

/// Inverse of to_bae_control() on unit vectors: BAE control colours in [0, 1] -> view-space
/// normals in the OpenGL camera convention (x right), renormalized.
Image from_bae_control(const Image& control);

/// A guidance prior: refines a batch of renders into targets.
class GuidanceBackend {
public:
    virtual ~GuidanceBackend();

    /// The name create() knows this backend by (e.g. "exemplar_patch_match").
    virtual std::string name() const = 0;
    /// Whether refine() accepts requests of `kind`.
    virtual bool supports(GuidanceKind kind) const = 0;
    /// Refines request.images into targets. Deterministic for a given request (seed included).
    /// Throws tdf::Error for unsupported kinds, malformed requests, or external failures.
    virtual GuidanceResult refine(const GuidanceRequest& request) = 0;
    /// Gives the backend the touched tactile exemplars: tangent-space normal maps (OpenGL
    /// convention, green = up), 3 channels in [-1, 1]. Backends that build on them
    /// (exemplar_patch_match) replace their exemplars; the others ignore the call, so a trainer
    /// can always make it. Throws tdf::Error for unusable exemplars.
    virtual void set_exemplars(std::vector<Image> tangent_normals) { (void)tangent_normals; }

    /// Creates a backend by name from its JSON config object (unknown keys are an error):
    /// "none" -> nullptr (guidance disabled), "exemplar_patch_match", "relief_shading",
    /// "external". Throws tdf::Error naming the backend for unknown names or bad configs.
    /// Config keys of each backend are documented in its header and in docs/guidance-backends.md.
    static std::unique_ptr<GuidanceBackend> create(const std::string& name, const Json& config);
    /// The names create() accepts, "none" first.
    static std::vector<std::string> names();
};

}  // namespace tdf
