#pragma once
/// The guidance schedule and prompts of the reference (spec 5.1, 5.4, 5.5, 5.7, 13.21).
///
/// Iteration numbering: the loop index `i` runs 0..iters_total-1; the reference's internal step
/// counter is `step = i + 1`. Visual guidance is on for i >= iters_init (150), tactile guidance
/// for i > iters_init (151..199).
#include <string>
#include <vector>

namespace tdf {

/// Number of DDIM steps of the reference's refine() calls (spec 5.4).
constexpr int kGuidanceDdimSteps = 50;
/// Visual strength at the start and the end of the refinement (`sd_guidance_strength`,
/// `max_guidance_strength`, spec 5.4).
constexpr double kVisualStrengthStart = 0.5;
constexpr double kVisualStrengthEnd = 0.7;
/// Tactile strength (`tactile_guidance_multistep_strength`, spec 5.5): noise at t = 181.
constexpr double kTactileGuidanceStrength = 0.8;

/// `min(1, (step - iters_init) / (iters_total - iters_init))` with step = i + 1, computed in
/// double precision as the reference does (the floor in ddim_start_index() depends on it,
/// spec 13.21). Requires iters_total > iters_init. Negative before the refinement starts.
double step_ratio(int iteration, int iters_init, int iters_total);

/// Whether visual guidance runs at loop index `iteration`: i >= iters_init (spec 5.1).
inline bool visual_guidance_active(int iteration, int iters_init = 150) { return iteration >= iters_init; }
/// Whether tactile guidance runs at loop index `iteration`: i > iters_init (spec 5.1, 9).
inline bool tactile_guidance_active(int iteration, int iters_init = 150) { return iteration > iters_init; }

/// Visual guidance strength at loop index `iteration`:
/// `0.5 + step_ratio * (0.7 - 0.5)` (spec 5.4), 0.504 at i = 150, 0.7 at i = 199.
double visual_guidance_strength(int iteration, int iters_init = 150, int iters_total = 200);

/// The DDIM timesteps of an `steps`-step schedule over 1000 training steps with leading spacing
/// and steps_offset 1 (spec 5.4): 981, 961, ..., 1 for 50 steps.
std::vector<int> ddim_timesteps(int steps = kGuidanceDdimSteps);

/// The reference's start index into ddim_timesteps(): `int(steps * strength)` (spec 5.4).
/// Larger strength = later start = less noise (spec 13.21).
int ddim_start_index(double strength, int steps = kGuidanceDdimSteps);
/// The timestep at which noise is added: ddim_timesteps(steps)[ddim_start_index()]
/// (481 at strength 0.504, 181 at 0.8).
int ddim_start_timestep(double strength, int steps = kGuidanceDdimSteps);
/// Fraction of the schedule that is denoised, `(steps - start_index) / steps`: the "strength" of
/// diffusers img2img and of stable-diffusion.cpp `--strength` (0.5 at reference strength 0.504,
/// 0.2 at 0.8). Built-in backends scale their effect with it.
double denoise_fraction(double strength, int steps = kGuidanceDdimSteps);

/// The fixed negative prompt of the reference (spec 5.7).
extern const char* const kNegativePrompt;
/// The suffix appended to every generated prompt (spec 5.7).
extern const char* const kPromptSuffix;
/// Prompt and negative prompt used by the reference's tactile guidance (spec 5.5).
extern const char* const kTactilePrompt;

/// One entry of the reference's `texture_desc.json` (spec 5.7).
struct TextureDescription {
    const char* texture;      ///< texture key, e.g. "GreenSweater"
    const char* description;  ///< e.g. "crochet"
};
/// All 28 entries, in the file's order.
const std::vector<TextureDescription>& texture_descriptions();
/// The description of `texture` (case-sensitive, e.g. "avocado" -> "avocado skin's").
/// Throws tdf::Error listing the known keys for an unknown texture.
std::string texture_description(const std::string& texture);

/// Object words of a mesh name (the mesh file's parent folder, spec 1.1): split on '_', drop
/// tokens made only of digits and the tokens "RichDreamer" / "InstantMesh", join with spaces.
/// "an_avocado_2" -> "an avocado".
std::string object_words(const std::string& mesh_obj);

/// Single-texture prompt (spec 5.7): "<object words> with <description> texture" + kPromptSuffix.
/// "an_avocado_2", "avocado" -> "an avocado with avocado skin's texture, highly detailed, hd,
/// best quality, front lighting".
std::string textured_prompt(const std::string& mesh_obj, const std::string& texture);

/// A multi-part prompt and the CLIP token indices of the two part names (BOS = index 0).
struct MultiPartPrompt {
    std::string prompt;
    int part_a_token = 0;
    int part_b_token = 0;
};
/// Multi-part prompt (spec 5.7): "<object description>, <partA> with <descA> texture, <partB>
/// with <descB> texture" + kPromptSuffix, for the seven meshes the reference hard-codes.
/// Throws tdf::Error for other meshes (the reference aborts) or unknown textures.
MultiPartPrompt multi_part_prompt(const std::string& mesh_obj, const std::string& texture_a,
                                  const std::string& texture_b);

}  // namespace tdf
