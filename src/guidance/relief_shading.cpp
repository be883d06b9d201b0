#include <tdf/guidance/relief_shading.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/image_ops.h>
#include <tdf/guidance/schedule.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {
/// Divergence below which a pixel counts as flat (1 / pixel): a normal turning by 0.06 degrees
/// per pixel, far below visible relief and above float noise.
constexpr float kFlatCurvature = 1e-3f;
}  // namespace

ReliefShadingBackend::Options ReliefShadingBackend::Options::from_json(const Json& config) {
    ConfigReader reader(config, "guidance backend 'relief_shading'");
    Options o;
    o.contrast = reader.get<float>("contrast", o.contrast);
    o.detail_sigma = reader.get<float>("detail_sigma", o.detail_sigma);
    o.curvature_sigma = reader.get<float>("curvature_sigma", o.curvature_sigma);
    o.curvature_percentile = reader.get<float>("curvature_percentile", o.curvature_percentile);
    o.curvature_limit = reader.get<float>("curvature_limit", o.curvature_limit);
    if (reader.has("anchor")) {
        const std::string anchor = reader.require<std::string>("anchor");
        if (anchor == "reference") o.anchor = Anchor::Reference;
        else if (anchor == "current") o.anchor = Anchor::Current;
        else throw_error("{}: anchor must be \"reference\" or \"current\", got '{}'", reader.where(), anchor);
    }
    reader.check_all_read();
    if (!(o.contrast >= 0.0f && o.contrast <= 1.0f))
        throw_error("{}: contrast {} is outside [0, 1]", reader.where(), o.contrast);
    if (!(o.detail_sigma > 0.0f && o.detail_sigma <= 32.0f))
        throw_error("{}: detail_sigma {} is outside (0, 32]", reader.where(), o.detail_sigma);
    if (!(o.curvature_sigma >= 0.0f && o.curvature_sigma <= 32.0f))
        throw_error("{}: curvature_sigma {} is outside [0, 32]", reader.where(), o.curvature_sigma);
    if (!(o.curvature_percentile > 0.0f && o.curvature_percentile <= 1.0f))
        throw_error("{}: curvature_percentile {} is outside (0, 1]", reader.where(), o.curvature_percentile);
    if (!(o.curvature_limit >= 1.0f && o.curvature_limit <= 1000.0f))
        throw_error("{}: curvature_limit {} is outside [1, 1000]", reader.where(), o.curvature_limit);
    return o;
}

ReliefShadingBackend::ReliefShadingBackend(Options options) : m_options(options) {}

Image normal_divergence(const Image& viewspace_normals, const Image& mask, float sigma) {
    const int w = viewspace_normals.width(), h = viewspace_normals.height();
    TDF_CHECK_EQ(viewspace_normals.channels(), 3);
    TDF_CHECK(mask.width() == w && mask.height() == h && mask.channels() == 1);
    const Image n = gaussian_blur_masked(viewspace_normals, mask, sigma);
    Image div(w, h, 1);
    const auto inside = [&](int x, int y) {
        return x >= 0 && y >= 0 && x < w && y < h && mask.at(x, y, 0) >= 0.5f;
    };
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < w; ++x) {
                if (!inside(x, y) || !inside(x - 1, y) || !inside(x + 1, y) || !inside(x, y - 1) ||
                    !inside(x, y + 1))
                    continue;
                const float dnx_dx = 0.5f * (n.at(x + 1, y, 0) - n.at(x - 1, y, 0));
                // Rows go down, view-space y goes up (spec 3.5): d/dy_up = -d/drow.
                const float dny_dy = -0.5f * (n.at(x, y + 1, 1) - n.at(x, y - 1, 1));
                div.at(x, y, 0) = dnx_dx + dny_dy;
            }
    });
    return div;
}

GuidanceResult ReliefShadingBackend::refine(const GuidanceRequest& request) {
    if (request.kind != GuidanceKind::Visual)
        throw_error("guidance backend 'relief_shading' handles visual requests only, got a {} request",
                    guidance_kind_name(request.kind));
    validate_request(request, "guidance backend 'relief_shading'");
    const float f = float(denoise_fraction(request.strength));
    GuidanceResult result;
    result.refined.resize(request.images.size());
    const auto refine_item = [&](std::size_t item) {
        const Image& colour = request.images[item];
        const Image& mask = request.masks[item];
        // The relief's own curvature: with the surface normals under it (GuidanceRequest::
        // surface_normals) the mesh's curvature is taken out, so a curved but untouched surface
        // (a sphere's flat-relief half) gets no shading, and the shading's contrast does not
        // follow the colour's edges there.
        Image normals = from_bae_control(request.control[item]);
        if (!request.surface_normals.empty()) {
            const Image& surface = request.surface_normals[item];
            for (std::size_t i = 0; i < normals.values().size(); ++i) normals.values()[i] -= surface.values()[i];
        }
        const Image curvature = normal_divergence(normals, mask, m_options.curvature_sigma);

        // Normalise by a quantile over the curved foreground pixels only, so sparse relief on a
        // flat surface is not drowned by the zeros; a flat surface has none and stays unchanged.
        std::vector<float> magnitudes;
        magnitudes.reserve(curvature.pixel_count());
        for (std::size_t p = 0; p < curvature.pixel_count(); ++p) {
            const float magnitude = std::abs(curvature.data()[p]);
            if (mask.data()[p] >= 0.5f && magnitude > kFlatCurvature) magnitudes.push_back(magnitude);
        }
        float scale = 0.0f;
        if (!magnitudes.empty()) {
            const auto rank = std::size_t(double(magnitudes.size() - 1) * m_options.curvature_percentile);
            std::nth_element(magnitudes.begin(), magnitudes.begin() + std::ptrdiff_t(rank), magnitudes.end());
            scale = magnitudes[rank];
        }

        // Relief detail as a RELATIVE change of the colour (issue 29): the target is the base
        // render times (1 + f contrast k'), k' the clamped curvature minus its local mean (pure
        // detail: the local mean colour is kept). The render is albedo x shade, so the albedo the
        // optimizer learns from it is albedo x (1 + f contrast k') whatever the light: the light of
        // the training views cannot leak into the albedo, dark stays dark (a black texel changes by
        // a fraction of almost nothing) and a saturated one keeps its hue (every channel scales
        // alike). The earlier additive form, contrast k (1 - L) toward white on ridges, learned as
        // k / shade, lit up dark albedo most and followed the light.
        // With the input's render (GuidanceRequest::reference_images) the change is applied to
        // what the input looks like, so repeated refinement converges to input x (1 + relief)
        // and never erases the input's own detail (faces, prints, logos); without it, the
        // current render's detail is partly replaced by relief detail on its local mean.
        const bool anchored = !request.reference_images.empty() && m_options.anchor == Options::Anchor::Reference;
        const Image& base = anchored ? request.reference_images[item] : colour;
        Image relief(colour.width(), colour.height(), 1);
        for (std::size_t p = 0; p < colour.pixel_count(); ++p)
            relief.data()[p] = scale > 0.0f ? std::clamp(curvature.data()[p] / scale, -m_options.curvature_limit,
                                                         m_options.curvature_limit)
                                            : 0.0f;
        const Image relief_mean = gaussian_blur_masked(relief, mask, m_options.detail_sigma);
        const Image local_mean = anchored ? Image() : gaussian_blur_masked(colour, mask, m_options.detail_sigma);

        Image out(colour.width(), colour.height(), 3);
        for (std::size_t p = 0; p < colour.pixel_count(); ++p) {
            const float m = mask.data()[p];
            float* dst = out.data() + 3 * p;
            if (m == 0.0f) {
                // Matches reference: refined background forced to white (spec 5.4).
                dst[0] = dst[1] = dst[2] = 1.0f;
                continue;
            }
            const float gain = 1.0f + f * m_options.contrast * (relief.data()[p] - relief_mean.data()[p]);
            for (int c = 0; c < 3; ++c) {
                const std::size_t i = 3 * p + std::size_t(c);
                const float v = colour.data()[i];
                float refined = 0.0f;
                if (anchored) {
                    refined = base.data()[i] * gain;
                } else {
                    // The gain acts on the local mean only: the render's own detail shrinks by
                    // (1 - f) per call, so repeated refinement converges to L (1 + contrast k')
                    // instead of compounding the gain.
                    const float mean = local_mean.data()[i];
                    refined = mean * gain + (1.0f - f) * (v - mean);
                }
                dst[c] = std::clamp(m * refined + (1.0f - m) * v, 0.0f, 1.0f);
            }
        }
        result.refined[item] = std::move(out);
    };
    // The images are independent: refined in parallel (each also parallel inside its blurs).
    parallel_for(request.images.size(), 1, [&](std::size_t first, std::size_t last) {
        for (std::size_t item = first; item < last; ++item) refine_item(item);
    });
    return result;
}

double colour_geometry_correlation(const Image& colour, const Image& viewspace_normals, const Image& mask) {
    const Image low = gaussian_blur_masked(colour, mask, 3.0f);
    const Image curvature = normal_divergence(viewspace_normals, mask, 1.0f);
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    std::size_t n = 0;
    for (std::size_t p = 0; p < colour.pixel_count(); ++p) {
        if (mask.data()[p] < 1.0f) continue;
        double a = 0;
        for (int c = 0; c < 3; ++c) a += (colour.data()[3 * p + std::size_t(c)] - low.data()[3 * p + std::size_t(c)]) / 3.0;
        const double b = curvature.data()[p];
        sa += a, sb += b, saa += a * a, sbb += b * b, sab += a * b, ++n;
    }
    if (n == 0) return 0.0;
    const double cov = sab / double(n) - sa / double(n) * sb / double(n);
    const double va = saa / double(n) - sa / double(n) * sa / double(n);
    const double vb = sbb / double(n) - sb / double(n) * sb / double(n);
    return va > 0 && vb > 0 ? cov / std::sqrt(va * vb) : 0.0;
}

}  // namespace tdf
