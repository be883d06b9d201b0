#include <tdf/guidance/guidance_frames.h>

#include <tdf/io/image_io.h>

#include <fmt/format.h>

namespace tdf {

namespace {
Image normals_for_display(const Image& normals) {
    Image out = normals;
    for (float& v : out.values()) v = (v + 1.0f) * 0.5f;
    return out;
}
}  // namespace

std::vector<std::string> save_guidance_frames(const std::string& folder, int iteration,
                                              const GuidanceRequest& request, const GuidanceResult& result) {
    const bool visual = request.kind == GuidanceKind::Visual;
    std::vector<std::string> written;
    const auto save = [&](const char* key, std::size_t k, const Image& image) {
        const std::string path = fmt::format("{}/{}/{:05d}_{}.png", folder, key, iteration, k);
        write_png(path, image);
        written.push_back(path);
    };
    for (std::size_t k = 0; k < request.images.size(); ++k) {
        if (visual) {
            save("rendered_lambertians", k, request.images[k]);
            if (k < request.control.size()) save("controlnet_control_images", k, request.control[k]);
        } else {
            save("rendered_perturb_normals", k, normals_for_display(request.images[k]));
        }
        if (k < request.masks.size())
            save(visual ? "rendered_masks" : "rendered_masks_patch", k, request.masks[k]);
        if (k < result.refined.size())
            save(visual ? "controlnet_refined_images" : "rendered_guidance_perturb_normals",
                 k,
                 visual ? result.refined[k] : normals_for_display(result.refined[k]));
    }
    return written;
}

}  // namespace tdf
