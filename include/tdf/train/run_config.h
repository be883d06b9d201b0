#pragma once
/// Settings of `tdf optimize`, read from the scene file's "optimize", "tactile_layout" and
/// "export" sections. Every default is the reference's value (spec 2.3, 2.4, 4.4, 5.1-5.5)
/// unless its comment says otherwise; docs/scene-format.md lists them all.
#include <tdf/atlas/surface_height.h>
#include <tdf/core/config.h>

#include <cstdint>
#include <string>

namespace tdf {

struct LossWeights {
    float albedo_init = 1.0f;         ///< per-pixel MSE weight, iterations [0, init]  (spec 5.2)
    /// Mean-colour MSE weight after init (spec 5.2): 500 in the reference schedule; 0 in the
    /// texture schedule, whose Jacobi step is a per-texel (diagonal) update that a global term
    /// would make overshoot, and whose anchored visual guidance keeps the input's colours anyway.
    float albedo_refine = 0.0f;
    float tactile_init = 1.0f;        ///< 1 - cos weight during init                  (spec 5.3)
    float tactile_refine = 0.1f;      ///< 1 - cos weight during refinement            (spec 5.3, 13.2)
    float tactile_guidance = 0.05f;   ///< tactile guidance weight, from init + 2      (spec 5.5)
    float visual_guidance = 5.0f;     ///< x (L1 + structural), from init + 1          (spec 5.4)
    float visual_guidance_structural = 1.0f;  ///< weight of the SSIM term inside visual guidance
    /// Texture evaluation, matching phase: dense texture-space terms against the targets laid over
    /// the atlas: albedo MSE and tactile 1 - cos, per texel.
    float texture_albedo = 1.0f;
    float texture_tactile = 1.0f;
};

enum class TactileLayout {
    Atlas,     ///< the map covers the UV atlas once, as the reference does (spec 1.3.5)
    Physical,  ///< the map repeats at its real size: mm per texel from the map, mm per mesh unit
};

enum class TactileGuidanceLoss { Cosine, Mse };

/// Where the texture field is evaluated during training ("field.evaluation").
enum class FieldEvaluation {
    /// Default: once per atlas texel; views and patches sample the learned maps with the
    /// renderer's filtering and send gradients back through its adjoint (issue 10).
    Texture,
    /// The reference: at every ray hit of every view, baked into maps only at export (spec 4.3).
    Pixel,
};

struct RunConfig {
    /// "schedule": "texture" (default: texture-space evaluation, a dense matching phase of
    /// 100 iterations on texel samples, 25 refinement iterations) or "reference" (the paper's
    /// 150 + 50 per-pixel iterations, field.evaluation = pixel). Keys given explicitly win.
    std::string schedule = "texture";
    FieldEvaluation evaluation = FieldEvaluation::Texture;
    /// Total iterations (reference schedule: 200, spec 5.1 iters_refine). The texture schedule's 25
    /// refinement iterations measure as 50 did on every quality number (docs/measurements.md,
    /// "The main job by stage": the Jacobi step converges in a few visits of each texel).
    int iterations = 125;
    int init_iterations = 100;      ///< matching phase length (reference schedule: 150, spec 5.1 iters_init)
    /// Texture evaluation: texels per matching iteration (random sample of the atlas's texels)
    /// on which the grid is fitted to the texture-space targets.
    int fit_texels = 1 << 16;
    /// Texture evaluation: keep training the grid during refinement (costs a field forward and
    /// backward over every texel per iteration); false trains only the per-texel residual there.
    bool refine_grid = false;
    /// Texture evaluation: how the per-texel residual is updated in refinement. "jacobi"
    /// (default): every texel seen this iteration moves by `residual_step` times the
    /// coverage-weighted mean of what its pixels ask for (the gradient divided by the loss's
    /// curvature summed over the texel's footprint: a diagonal Gauss-Newton step), texels not
    /// seen do not move; "adam": Adam at `learning_rate` (per-texel sign-like steps: speckle).
    std::string residual_optimizer = "jacobi";
    float residual_step = 0.5f;
    /// Passes of a [1 2 1] / 4 tent over the Jacobi step's albedo gradient and curvature
    /// ("field.residual_step_smoothing", 0-8): views that read coarse mip levels would otherwise
    /// move 2x2 blocks of texels together and leave their edges in the exported map.
    int residual_step_smoothing = 2;
    /// Texture evaluation: texels (at the map size) over which the tactile map laid per chart is
    /// cross-faded with the neighbouring chart's across every UV seam ("field.tactile_seam_band",
    /// 0-64; 0 keeps the reference's per-chart layout): tactile_seam_blend.h.
    float tactile_seam_band = 8.0f;
    /// The visual guidance loss: "l1_structural" (reference: L1 + structural term, spec 5.4) or
    /// "mse" (texture schedule default: a squared error, whose gradient says how far each
    /// pixel is from its target, which the Jacobi step needs).
    std::string visual_guidance_loss = "mse";
    /// log2 of the hash table entries per level ("field.table_log2"; reference 15, spec 4.1).
    int table_log2 = 15;
    int batch_size = 4;             ///< visual views per iteration (spec 2.3)
    int patch_batch_size = 4;       ///< tactile patches per iteration (spec 2.4)
    int resolution = 512;           ///< visual render size (spec 2.3)
    /// Tactile patch render size in pixels (spec 2.4: 512). "auto" (patch_resolution_auto, the
    /// texture schedule's default) sizes it from the learned maps' texel density once the mesh is
    /// known (auto_patch_resolution): the reference's 512 px sample a 1024^2 map's texels with
    /// 9.6 (pebble sphere) to 12.5 (mug) pixels a side, four patches being about 40 % of a
    /// refinement iteration (docs/commands/optimize.md, "Patch resolution").
    int patch_resolution = 512;
    bool patch_resolution_auto = true;
    float patch_half_extent = 0.075f;  ///< half side of the orthographic patch window, mesh units (spec 2.4)
    float patch_distance = 0.1f;    ///< patch camera height above the surface, mesh units (spec 2.4)
    /// Random SSAA factor in [1, max] (spec 2.3); 1 = off. 2 in the reference schedule; 1 in the
    /// texture schedule, where visual views only carry guidance: the maps are sampled with their
    /// mips at the view's footprint either way, and SSAA would cost up to 4x their pixels.
    float max_ssaa = 1.0f;
    float learning_rate = 0.01f;    ///< Adam lr (spec 4.4)
    /// The training views' point light ("optimize.training_light"): "random" (the reference's
    /// magic3d draw per view, spec 3.4) or an object {"elevation_degrees", "azimuth_degrees",
    /// "distance"} that fixes it in every view's magic3d frame (theta, phi, d of
    /// magic3d_light); the random draw is still made, so the views are the same either way.
    /// What the refinement learns must not depend on it (issue 29's light test).
    bool fixed_training_light = false;
    float light_elevation_degrees = 60.0f, light_azimuth_degrees = 0.0f, light_distance = 4.0f;
    /// The refinement's colour bound (albedo_range.h, issue 29): every albedo texel stays within
    /// the input albedo's per-channel range over the (2 r + 1)^2 texels of its chart around it,
    /// widened by `lighten` above and `darken` below ("optimize.albedo_range_radius" r, 0 = no
    /// bound; "optimize.albedo_range_lighten", "optimize.albedo_range_darken"). Nothing gets
    /// brighter than its neighbourhood by more than `lighten` (no highlight can be painted in,
    /// dark stays dark, a saturated colour cannot turn pale); cavities may darken further, which
    /// is what relief-aligned colour mostly is.
    int albedo_range_radius = 1;
    float albedo_range_lighten = 0.04f;
    float albedo_range_darken = 0.08f;
    LossWeights weights;
    TactileGuidanceLoss tactile_guidance_loss = TactileGuidanceLoss::Cosine;  ///< paper; Mse = code
    int checkpoint_every = 50;      ///< iterations between checkpoints (0 = only at phase ends)
    int held_out_views = 4;         ///< views never used for training, for the quality report
    int held_out_patches = 4;
    bool field_raw_coordinates = false;  ///< reference: grid fed raw coordinates (spec 4.1)

    TactileLayout tactile_layout = TactileLayout::Atlas;
    float mm_per_unit = 0.0f;       ///< Physical layout: millimetres per mesh unit (required there)
    float tactile_mm_per_pixel = 0.0f;  ///< overrides the map's own metadata when > 0

    int texture_size = 1024;        ///< baked map size (spec 1.4)
    int gutter = 8;                 ///< texels of dilation across seams in the bakes
    bool write_glb = true;
    bool write_exr = true;
    /// The texel size the exported height map's slopes are integrated over (export.height_texel_size:
    /// "map" = the map's one size, seams levelled; "surface" = each texel's own on the mesh).
    HeightMetric height_metric = HeightMetric::Map;
    int turntable_views = 8;        ///< PNG turntable renders of the result (0 = none)
    int turntable_resolution = 512;

    std::string guidance_visual = "relief_shading";          ///< guidance backend names
    std::string guidance_tactile = "exemplar_patch_match";
    Json guidance_config = Json::object();  ///< the raw "guidance" section for the backends
    bool save_guidance_frames = false;

    /// Reads the sections (each may be absent); unknown keys are errors naming `source`. The
    /// `schedule` preset is applied first, so keys given explicitly override it.
    static RunConfig from_json(const Json& optimize, const Json& tactile_layout, const Json& exporting,
                               const Json& guidance, const std::string& source, const Json& field = Json(),
                               const Json& schedule = Json());
    /// The resolved configuration, every key present, for `<name>_config.json` and the log.
    Json to_json() const;
    /// Checks ranges; throws tdf::Error naming the key.
    void validate(const std::string& source) const;
};

struct TriangleMesh;

/// The patch size "auto" stands for: kAutoPatchPixelsPerTexel pixels a side for each texel of the
/// learned maps (export.texture_size over the mesh's UV layout) across the patch window, rounded
/// up to a multiple of 32 and kept within [64, 512] (512 is the reference's size). 512 when the
/// mesh has no UV area.
constexpr int kAutoPatchPixelsPerTexel = 4;
int auto_patch_resolution(const TriangleMesh& mesh, const RunConfig& config);
/// Texels of the learned maps across the patch window (0 when the mesh has no UV area).
double patch_window_texels(const TriangleMesh& mesh, const RunConfig& config);

}  // namespace tdf
