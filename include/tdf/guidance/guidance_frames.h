#pragma once
/// Debug frames of the guidance calls, like the reference's debug videos (spec 8.2): per call,
/// PNG frames of what went in and what came out, so a user can see what guided the run.
/// Turn a folder of frames into a video with e.g.
///   ffmpeg -framerate 3 -pattern_type glob -i 'controlnet_refined_images/*_0.png' refined.mp4
#include <tdf/guidance/guidance_backend.h>

#include <string>
#include <vector>

namespace tdf {

/// Writes `<folder>/<key>/<iteration, 5 digits>_<k>.png` for every image k of the call, with the
/// reference's video keys as folder names (spec 8.2):
///  - visual:  rendered_lambertians (input), controlnet_control_images (control),
///             rendered_masks, controlnet_refined_images (result);
///  - tactile: rendered_perturb_normals (input), rendered_masks_patch,
///             rendered_guidance_perturb_normals (result).
/// Normals are shown as (n + 1) / 2 as in the reference's videos; 8-bit, truncated as the
/// reference's `astype(uint8)` (spec 13.20); full resolution (the reference resizes to 256).
/// `result` may be empty (inputs only, e.g. when the backend failed). Returns the paths written.
std::vector<std::string> save_guidance_frames(const std::string& folder, int iteration,
                                              const GuidanceRequest& request, const GuidanceResult& result);

}  // namespace tdf
