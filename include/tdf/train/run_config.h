#pragma once
/// Settings of `tdf optimize`, read from the scene file's "optimize", "tactile_layout" and
/// "export" sections. Every default is the reference's value (spec 2.3, 2.4, 4.4, 5.1-5.5)
/// unless its comment says otherwise; README "Scene file format" lists them all.
#include <tdf/core/config.h>

#include <cstdint>
#include <string>

namespace tdf {

struct LossWeights {
    float albedo_init = 1.0f;         ///< per-pixel MSE weight, iterations [0, init]  (spec 5.2)
    float albedo_refine = 500.0f;     ///< mean-colour MSE weight after init          (spec 5.2)
    float tactile_init = 1.0f;        ///< 1 - cos weight during init                  (spec 5.3)
    float tactile_refine = 0.1f;      ///< 1 - cos weight during refinement            (spec 5.3, 13.2)
    float tactile_guidance = 0.05f;   ///< tactile guidance weight, from init + 2      (spec 5.5)
    float visual_guidance = 5.0f;     ///< x (L1 + structural), from init + 1          (spec 5.4)
    float visual_guidance_structural = 1.0f;  ///< weight of the SSIM term inside visual guidance
};

enum class TactileLayout {
    Atlas,     ///< the map covers the UV atlas once, as the reference does (spec 1.3.5)
    Physical,  ///< the map repeats at its real size: mm per texel from the map, mm per mesh unit
};

enum class TactileGuidanceLoss { Cosine, Mse };

struct RunConfig {
    int iterations = 200;           ///< total iterations (spec 5.1 iters_refine)
    int init_iterations = 150;      ///< matching phase length (spec 5.1 iters_init)
    int batch_size = 4;             ///< visual views per iteration (spec 2.3)
    int patch_batch_size = 4;       ///< tactile patches per iteration (spec 2.4)
    int resolution = 512;           ///< visual render size (spec 2.3)
    int patch_resolution = 512;     ///< tactile patch render size (spec 2.4)
    float patch_half_extent = 0.075f;  ///< half side of the orthographic patch window, mesh units (spec 2.4)
    float patch_distance = 0.1f;    ///< patch camera height above the surface, mesh units (spec 2.4)
    float max_ssaa = 2.0f;          ///< random SSAA factor in [1, max] (spec 2.3); 1 = off
    float learning_rate = 0.01f;    ///< Adam lr (spec 4.4)
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
    int turntable_views = 8;        ///< PNG turntable renders of the result (0 = none)
    int turntable_resolution = 512;

    std::string guidance_visual = "relief_shading";          ///< guidance backend names
    std::string guidance_tactile = "exemplar_patch_match";
    Json guidance_config = Json::object();  ///< the raw "guidance" section for the backends
    bool save_guidance_frames = false;

    /// Reads the three sections (each may be absent); unknown keys are errors naming `source`.
    static RunConfig from_json(const Json& optimize, const Json& tactile_layout, const Json& exporting,
                               const Json& guidance, const std::string& source);
    /// The resolved configuration, every key present, for `<name>_config.json` and the log.
    Json to_json() const;
    /// Checks ranges; throws tdf::Error naming the key.
    void validate(const std::string& source) const;
};

}  // namespace tdf
