#pragma once
/// Tactile guidance without weights: exemplar-based texture optimization (Kwatra et al. 2005,
/// "Texture Optimization for Example-based Synthesis") with a PatchMatch search (Barnes et al.
/// 2009). The refined target of a rendered tactile patch is rebuilt from the nearest patches of
/// the touched exemplars, so the learned normals are pulled toward the statistics of what was
/// touched, which is the role TextureDreambooth plays in the reference (spec 5.5).
///
/// Algorithm, per image of the request (parallel over pixels; deterministic for a seed and
/// independent of the thread count):
///  1. Pyramids: the image, its mask and every exemplar variant are box-downsampled `levels`
///     times (coarsest first; levels whose images get smaller than two patches are dropped).
///  2. At each level the starting estimate is the input at that level plus the change the coarser
///     level made (Laplacian transfer), so the input's structure is kept and only its texture is
///     replaced; the nearest-neighbour field (NNF) is initialised randomly at the coarsest level
///     and upsampled from the coarser level afterwards.
///  3. `em_iterations` times: PatchMatch (Jacobi-style, every pixel reads the previous NNF:
///     propagation from neighbours at jump-flood offsets, then random search around the best
///     match, `search_iterations` rounds) over the exemplar variants, minimising the mask-weighted
///     sum of squared differences of the normal vectors over a `patch_size`^2 window; then
///     voting: each pixel becomes the average of the exemplar pixels that the patches covering it
///     propose, renormalized to unit length.
///  4. Output: foreground pixels get mask * voted unit normal (the antialiased convention of the
///     renders, spec 3.6); pixels with mask 0 keep the input (background).
///
/// Rotation: a rendered patch shows VIEW-space normals from an orthographic camera along the
/// surface normal, i.e. tangent space up to an unknown in-plane rotation (the patch camera's
/// roll) and, in the reference, a vertical flip of the rows that leaves the vectors unchanged
/// (spec 13.13). The search therefore runs over exemplar variants: `rotations` in-plane rotations
/// (multiples of 360/rotations degrees; the image is resampled bilinearly and the (x, y)
/// components of every normal are rotated with it; non-multiples of 90 degrees are cropped to the
/// largest axis-aligned square inside the rotated exemplar), each also with rows flipped when
/// `flip_rows` is set. Each pixel's match picks its own variant.
///
/// Limitation: the target keeps the input's structure at every scale (step 2), so the backend
/// sharpens and re-textures relief that is there (as after the reference's 150 iterations of
/// tactile matching) but does not create bumps on a flat input; a diffusion model with noise can.
///
/// The search is approximate (PatchMatch); content that exists in an exemplar variant is found
/// exactly (tested with 90-degree rotated crops). Cost grows with the image's pixels, not with the
/// exemplar's size: about 0.4 s CPU for a 256x256 patch and 1.8 s for 512x512 with the defaults
/// (README "Guidance backends"). Memory: every variant pyramid is kept, about
/// 16 bytes x exemplar pixels x rotations x (flip_rows ? 2 : 1).
#include <tdf/guidance/guidance_backend.h>

#include <string>
#include <vector>

namespace tdf {

class ExemplarPatchMatchBackend final : public GuidanceBackend {
public:
    static constexpr const char* kName = "exemplar_patch_match";

    /// Config keys (all optional except that exemplars must be given here or by set_exemplars()).
    struct Options {
        /// "exemplars": tangent-space normal maps (PNG: n = 2 * value - 1, alpha ignored, as
        /// the reference encodes them; EXR: raw vectors). OpenGL convention, green = up.
        std::vector<std::string> exemplar_files;
        /// "exemplar_scale": resampling factor applied to the exemplars before the search, in
        /// render pixels per exemplar pixel (2 = each exemplar pixel covers 2x2 render pixels).
        float exemplar_scale = 1.0f;
        /// "patch_size": odd window side in pixels (3..15).
        int patch_size = 7;
        /// "levels": pyramid levels (1 = finest only).
        int levels = 3;
        /// "em_iterations": search + vote rounds per level.
        int em_iterations = 2;
        /// "search_iterations": PatchMatch propagation + random-search rounds per search.
        int search_iterations = 4;
        /// "rotations": in-plane rotations searched: 1, 2, 4 or 8 (every 360/rotations degrees).
        int rotations = 4;
        /// "flip_rows": also search the row-flipped variants (spec 13.13).
        bool flip_rows = true;

        /// Reads the keys above; throws tdf::Error for unknown keys or bad values.
        static Options from_json(const Json& config);
    };

    /// Reads the exemplar files of `options` (if any).
    explicit ExemplarPatchMatchBackend(Options options);
    ~ExemplarPatchMatchBackend() override;

    /// Replaces the exemplars: tangent-space normal maps, 3 channels in [-1, 1] (or 4, alpha
    /// ignored). Builds the search variants and pyramids. Throws tdf::Error for exemplars
    /// smaller than a patch at the coarsest level.
    void set_exemplars(std::vector<Image> tangent_normals) override;
    std::size_t exemplar_count() const { return m_exemplar_count; }

    std::string name() const override { return kName; }
    bool supports(GuidanceKind kind) const override { return kind == GuidanceKind::Tactile; }
    /// Tactile requests only. `strength` is not used: the reference keeps the tactile strength
    /// constant (0.8, spec 5.5), and a projection onto the exemplar's patches has no noise level.
    GuidanceResult refine(const GuidanceRequest& request) override;

    /// Mean over the foreground pixels of `normals` (mask >= 0.5, whole window inside the image)
    /// of the squared distance from the pixel's patch to its nearest exemplar patch, found by
    /// brute force over every variant position. A statistic of how exemplar-like an image is;
    /// cost O(pixels x exemplar pixels x variants), meant for small test images.
    double mean_nearest_patch_distance(const Image& normals, const Image& mask) const;

    const Options& options() const { return m_options; }

    struct Variant;  // exemplar variant pyramid (defined in the .cpp)

private:
    Options m_options;
    std::size_t m_exemplar_count = 0;
    std::vector<Variant> m_variants;
};


}  // namespace tdf
