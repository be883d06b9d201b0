#pragma once
/// Visual guidance without weights: geometry-aware colour refinement. The normal-conditioned
/// ControlNet of the reference (spec 5.4) pushes the colour render toward an image whose colour
/// variation agrees with the tactile relief; this backend does the one part of that which needs no
/// learned prior: it replaces part of the render's fine colour variation with cavity/ridge shading
/// derived from the curvature of the view-space normal control image (darker cavities, lighter
/// ridges, as texture artists paint ambient occlusion), so that the albedo learned from the
/// target acquires variation aligned with the geometry. It cannot invent colours or semantics.
///
/// Per image (parallel over rows, deterministic):
///  1. n = from_bae_control(control), smoothed by a Gaussian of `curvature_sigma` pixels over the
///     foreground (mask-weighted, so the silhouette does not bleed in).
///  2. Curvature k = divergence of the (x, y) normal field, d n_x / d x + d n_y / d y with y up
///     (> 0 on ridges and bumps, < 0 in cavities), central differences, 0 where a neighbour is
///     background; divided by the `curvature_percentile` quantile of |k| over the curved
///     foreground pixels (|k| > 1e-3 per pixel) and clamped to [-limit, limit]
///     (`curvature_limit`; so the effect does not depend on resolution or relief height; a flat
///     surface gets no relief).
///  3. The relief detail k' is that normalised curvature minus its own local mean (mask-weighted
///     Gaussian, `detail_sigma` pixels): pure detail, so the local mean colour is kept.
///  4. With f = denoise_fraction(strength) (0.5 -> 0.3 over the visual schedule: more noise lets
///     the prior replace more of the input, spec 5.4), the relief is a RELATIVE change of the
///     colour, gain = 1 + f contrast k' (issue 29). When the request carries the input's render
///     (reference_images, `anchor: reference`, the default) c' = reference x gain: the input's own
///     detail (faces, prints, logos) stays and only relief-aligned variation is added, where the
///     relief is curved (issue 10 goal 2). Otherwise c' = L x gain + (1 - f)(c - L) with L the
///     render's local mean, which replaces part of the render's detail. Either way repeated
///     refinement converges instead of compounding. Clamped to [0, 1]. Because the render is
///     albedo x shade, the albedo learned from c' is the input's albedo x gain whatever the light
///     of the view, dark stays dark and every channel scales alike (the hue is kept).
///  5. Blend by coverage: out = m c' + (1 - m) c; pixels with mask exactly 0 are white (spec 5.4).
#include <tdf/guidance/guidance_backend.h>

namespace tdf {

class ReliefShadingBackend final : public GuidanceBackend {
public:
    static constexpr const char* kName = "relief_shading";

    struct Options {
        /// "contrast": how strong the relief-aligned colour is: the relative change of the colour
        /// at normalised curvature +-1 and full denoising (gain 1 +- contrast), [0, 1]; 0 = off
        /// (the refinement then keeps the input's colour). Scenes set it as
        /// guidance.relief_shading.contrast.
        float contrast = 0.25f;
        /// "detail_sigma": scale separating the local mean colour from detail, pixels (> 0).
        float detail_sigma = 3.0f;
        /// "curvature_sigma": Gaussian smoothing of the normals before differentiation, pixels.
        float curvature_sigma = 1.0f;
        /// "curvature_percentile": quantile of |curvature| (over curved pixels) mapped to 1, (0, 1].
        float curvature_percentile = 0.9f;
        /// "curvature_limit": the normalised curvature is clamped to +-this, [1, 1000]. A clamp
        /// at 1 flattens the profile of the strongest creases (ridges and grooves become plateaus
        /// of constant shading), which lowers the colour-geometry correlation it is meant to raise.
        float curvature_limit = 4.0f;
        /// "anchor": "reference" (default) adds the relief to the request's reference images (the
        /// input asset's render) when it has them: c' = reference + f R, so the input's own detail
        /// is kept and repeated refinement converges; "current" replaces part of the current
        /// render's detail (c' = L + (1 - f)(c - L) + f R, the behaviour before issue 10).
        enum class Anchor { Reference, Current };
        Anchor anchor = Anchor::Reference;

        /// Reads the keys above; throws tdf::Error for unknown keys or bad values.
        static Options from_json(const Json& config);
    };

    explicit ReliefShadingBackend(Options options);

    std::string name() const override { return kName; }
    bool supports(GuidanceKind kind) const override { return kind == GuidanceKind::Visual; }
    /// Visual requests only (needs the control images).
    GuidanceResult refine(const GuidanceRequest& request) override;

    const Options& options() const { return m_options; }

private:
    Options m_options;
};

/// Step 1-2 above without the normalisation: the divergence of the (x, y) components of
/// view-space normals (3 channels, x right, y up), per pixel, after mask-weighted Gaussian
/// smoothing with `sigma` pixels (0 = none). 1 channel; 0 on background pixels (mask < 0.5) and
/// where a neighbour is background. Units: 1 / pixel.
Image normal_divergence(const Image& viewspace_normals, const Image& mask, float sigma);

/// Colour-geometry alignment: the Pearson correlation, over pixels with mask 1, between the high
/// frequencies of the colour's luminance (colour minus its 3-pixel Gaussian blur) and the
/// curvature of the view-space normals (normal_divergence, sigma 1). Near 0 when colour detail
/// ignores the relief; positive when ridges are lighter and cavities darker (issue 6's measure).
double colour_geometry_correlation(const Image& colour, const Image& viewspace_normals, const Image& mask);

}  // namespace tdf
