#include <tdf/guidance/guidance_backend.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/vec.h>
#include <tdf/guidance/exemplar_patch_match.h>
#include <tdf/guidance/external_backend.h>
#include <tdf/guidance/relief_shading.h>

#include <cmath>

namespace tdf {

GuidanceBackend::~GuidanceBackend() = default;

const char* guidance_kind_name(GuidanceKind kind) {
    return kind == GuidanceKind::Visual ? "visual" : "tactile";
}

GuidanceKind parse_guidance_kind(const std::string& text, const std::string& where) {
    if (text == "visual") return GuidanceKind::Visual;
    if (text == "tactile") return GuidanceKind::Tactile;
    throw_error("{}: guidance kind '{}' is neither \"visual\" nor \"tactile\"", where, text);
}

namespace {
void check_image(const Image& image, int width, int height, int channels, const std::string& where,
                 const char* role, std::size_t index) {
    if (image.width() != width || image.height() != height || image.channels() != channels)
        throw_error("{}: {} {} is {}x{} with {} channels, expected {}x{} with {}",
                    where,
                    role,
                    index,
                    image.width(),
                    image.height(),
                    image.channels(),
                    width,
                    height,
                    channels);
    if (!image.all_finite()) throw_error("{}: {} {} has non-finite values", where, role, index);
}
}  // namespace

void validate_request(const GuidanceRequest& request, const std::string& where) {
    const std::size_t n = request.images.size();
    if (n == 0) throw_error("{}: the guidance request has no images", where);
    const int width = request.images[0].width();
    const int height = request.images[0].height();
    if (width <= 0 || height <= 0) throw_error("{}: image 0 is empty", where);
    for (std::size_t i = 0; i < n; ++i) check_image(request.images[i], width, height, 3, where, "image", i);
    if (request.masks.size() != n) throw_error("{}: {} masks for {} images", where, request.masks.size(), n);
    for (std::size_t i = 0; i < n; ++i) check_image(request.masks[i], width, height, 1, where, "mask", i);
    const std::size_t controls = request.kind == GuidanceKind::Visual ? n : 0;
    if (request.control.size() != controls)
        throw_error("{}: {} control images for {} {} images (visual requests need one each, tactile none)",
                    where,
                    request.control.size(),
                    n,
                    guidance_kind_name(request.kind));
    for (std::size_t i = 0; i < controls; ++i)
        check_image(request.control[i], width, height, 3, where, "control image", i);
    const std::size_t frames = request.surface_normals.size();
    const std::size_t tangents = request.surface_tangents.size();
    const bool frames_ok = request.kind == GuidanceKind::Tactile ? tangents == frames && (frames == 0 || frames == n)
                                                                 : tangents == 0 && (frames == 0 || frames == n);
    if (!frames_ok)
        throw_error("{}: {} surface normal and {} surface tangent images for {} {} images (tactile requests "
                    "have none or one of each per image, visual requests none or one surface normal image each)",
                    where,
                    frames,
                    request.surface_tangents.size(),
                    n,
                    guidance_kind_name(request.kind));
    const std::size_t references = request.reference_images.size();
    if ((references != 0 && references != n) || (references != 0 && request.kind != GuidanceKind::Visual))
        throw_error("{}: {} reference images for {} {} images (visual requests have none or one per image)", where,
                    references, n, guidance_kind_name(request.kind));
    for (std::size_t i = 0; i < references; ++i)
        check_image(request.reference_images[i], width, height, 3, where, "reference image", i);
    for (std::size_t i = 0; i < frames; ++i) check_image(request.surface_normals[i], width, height, 3, where, "surface normal image", i);
    for (std::size_t i = 0; i < tangents; ++i)
        check_image(request.surface_tangents[i], width, height, 4, where, "surface tangent image", i);
    if (!(request.pixels_per_texel >= 0.0f && std::isfinite(request.pixels_per_texel)))
        throw_error("{}: pixels_per_texel {} must be finite and >= 0", where, request.pixels_per_texel);
    if (!(request.strength >= 0.0 && request.strength <= 1.0))
        throw_error("{}: guidance strength {} is outside [0, 1]", where, request.strength);
}

void validate_result(const GuidanceRequest& request, const GuidanceResult& result, const std::string& where) {
    if (result.refined.size() != request.images.size())
        throw_error(
            "{}: {} refined images for {} inputs", where, result.refined.size(), request.images.size());
    for (std::size_t i = 0; i < result.refined.size(); ++i) {
        const Image& input = request.images[i];
        check_image(
            result.refined[i], input.width(), input.height(), input.channels(), where, "refined image", i);
    }
}

namespace {
/// Applies `convert` to every 3-vector of a 3-channel image.
template <typename Convert>
Image map_vectors(const Image& image, Convert convert) {
    TDF_CHECK_EQ(image.channels(), 3);
    Image out(image.width(), image.height(), 3, Image::Uninitialized{});
    const float* src = image.data();
    float* dst = out.data();
    parallel_for(image.pixel_count(), 1 << 14, [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p < end; ++p) {
            const Vec3f v = convert(Vec3f(src[3 * p], src[3 * p + 1], src[3 * p + 2]));
            dst[3 * p] = v.x, dst[3 * p + 1] = v.y, dst[3 * p + 2] = v.z;
        }
    });
    return out;
}
}  // namespace

Image to_bae_control(const Image& viewspace_normals) {
    return map_vectors(viewspace_normals, [](Vec3f n) {
        // Matches reference convert_normal2bae: exact-zero background -> (0,0,1), flip red,
        // F.normalize, (n + 1) / 2 (spec 5.4).
        if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) n = Vec3f(0.0f, 0.0f, 1.0f);
        n.x = -n.x;
        return (normalize_or_zero(n) + Vec3f(1.0f, 1.0f, 1.0f)) * 0.5f;
    });
}

Image from_bae_control(const Image& control) {
    return map_vectors(control, [](Vec3f c) {
        Vec3f n = c * 2.0f - Vec3f(1.0f, 1.0f, 1.0f);
        n.x = -n.x;
        return normalize_or_zero(n);
    });
}

std::vector<std::string> GuidanceBackend::names() {
    return {"none", ExemplarPatchMatchBackend::kName, ReliefShadingBackend::kName, ExternalBackend::kName};
}

std::unique_ptr<GuidanceBackend> GuidanceBackend::create(const std::string& name, const Json& config) {
    const Json& object = config.is_null() ? Json::object() : config;
    if (!object.is_object()) throw_error("guidance backend '{}': the config must be a JSON object", name);
    if (name == "none") {
        if (!object.empty())
            throw_error("guidance backend 'none' takes no config, got key '{}'", object.begin().key());
        return nullptr;
    }
    if (name == ExemplarPatchMatchBackend::kName)
        return std::make_unique<ExemplarPatchMatchBackend>(
            ExemplarPatchMatchBackend::Options::from_json(object));
    if (name == ReliefShadingBackend::kName)
        return std::make_unique<ReliefShadingBackend>(ReliefShadingBackend::Options::from_json(object));
    if (name == ExternalBackend::kName)
        return std::make_unique<ExternalBackend>(ExternalBackend::Options::from_json(object));
    std::string known;
    for (const auto& n : names()) known += (known.empty() ? "" : ", ") + n;
    throw_error("unknown guidance backend '{}' (known: {})", name, known);
}

}  // namespace tdf
