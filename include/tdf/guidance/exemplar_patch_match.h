#pragma once
/// Tactile guidance without weights: exemplar-based texture optimization (Kwatra et al. 2005,
/// "Texture Optimization for Example-based Synthesis") with a PatchMatch search (Barnes et al.
/// 2009). The refined target of a rendered tactile patch is rebuilt from the nearest patches of
/// the touched exemplars, so the learned normals are pulled toward the statistics of what was
/// touched, which is the role TextureDreambooth plays in the reference (spec 5.5).
///
/// Per image of the request (the images in parallel, each parallel over pixels; deterministic
/// for a seed and independent of the thread count):
///  1. Relief: with the request's surface frames (GuidanceRequest::surface_normals/tangents,
///     which tdf's optimizer provides), every normal is turned by the shortest rotation that
///     stands its surface normal upright, so the surface's curvature across the patch is not
///     mistaken for texture, and the exemplar is turned (and mirrored on charts of handedness
///     -1) the way the map lies in this patch: one orientation, no rotation search. Without
///     frames, or with `orientation: search`, the image is used as it is and the search runs
///     over `rotations` in-plane rotations of every exemplar (multiples of 360/rotations
///     degrees), each also row-flipped when `flip_rows` is set (the reference's upside-down
///     patches, spec 13.13); each pixel's match picks its own variant.
///  2. Scale: the exemplar is resampled so one of its texels spans as many pixels as the map's
///     texels do in the image (`exemplar_scale: auto` takes GuidanceRequest::pixels_per_texel).
///     Magnified more than 2x an exemplar's patches are smooth ramps that match anything, so
///     beyond that the image is searched as a coarser copy (at least three patches wide) and
///     the change the search makes there is added back to the full-size image. The copy is
///     prefiltered with a mask-weighted Gaussian of sigma 0.5 / shrink evaluated only at the
///     pixels the copy reads (gaussian_blur_resized), so its cost is a small fraction of a
///     full-size blur.
///  3. Synthesis (Kwatra et al.'s EM with a PatchMatch search and Kopf et al. 2007's histogram
///     matching): pyramids of `levels` levels (levels smaller than two patches are dropped).
///     The coarsest level starts from the image with a random nearest-neighbour field (NNF);
///     each finer level starts from its input plus the change the coarser level made (Laplacian
///     transfer), with the coarser matches carried down, so the relief stays where the image
///     has it. Then `em_iterations` times: the steepness histogram is matched to the
///     exemplar's (each foreground normal is ranked by tilt and takes the exemplar's tilt at
///     that quantile, keeping its azimuth; without it the averaging of votes washes the relief
///     out, which is what made this backend flatten learned normals before); PatchMatch
///     (Jacobi-style, every pixel reads the previous NNF: propagation at jump-flood offsets,
///     then random search around the best match, `search_iterations` rounds) minimising the
///     mask-weighted sum of squared differences of the normal vectors over a `patch_size`^2
///     window; voting: each pixel becomes the unit-length average of what the patches covering
///     it propose. The histogram is matched once more after the last vote.
///  4. Output: foreground pixels get mask * refined unit normal (turned back onto the surface;
///     the renders' antialiased convention, spec 3.6); pixels with mask 0 keep the input.
///
/// The coarsest level keeps the image's relief at the scale of a few patches, so the backend
/// sharpens and re-textures relief that is there (as after the reference's 150 iterations of
/// tactile matching) but does not create bumps on a flat input; a diffusion model with noise can.
///
/// The search is approximate (PatchMatch); content that exists in an exemplar variant is found
/// exactly (tested with 90-degree rotated crops). Cost grows with the working image's pixels, not
/// with the exemplar's size, except for turning the (scaled) exemplar for each image and sorting
/// its tilts, which are linear in the exemplar's pixels (docs/guidance-backends.md gives the
/// measured times). Memory: the search variants' pyramids, about 16 bytes x scaled exemplar
/// pixels x variants (surface variants: per image being refined).
#include <tdf/guidance/guidance_backend.h>

#include <cstdint>
#include <string>
#include <map>
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
        /// "exemplar_scale": render pixels per exemplar pixel, or "auto" (stored as 0, the
        /// default): the request's pixels_per_texel, 1 when the request does not say. A number
        /// in [0.125, 8] fixes it.
        float exemplar_scale = 0.0f;
        /// "orientation": "surface" (default) uses the request's surface frames when present;
        /// "search" always searches the rotations below.
        enum class Orientation { Surface, Search };
        Orientation orientation = Orientation::Surface;
        /// "patch_size": odd window side in pixels (3..15).
        int patch_size = 5;
        /// "levels": pyramid levels (1 = finest only).
        int levels = 2;
        /// "em_iterations": search + vote rounds per level. More rounds re-synthesise more of the
        /// image, which moves the target away from where the learned relief is: inside the
        /// optimizer one round pulls the statistics toward the exemplar best (docs/guidance-backends.md).
        int em_iterations = 1;
        /// "search_iterations": PatchMatch propagation + random-search rounds per search.
        int search_iterations = 8;
        /// "rotations": in-plane rotations searched without surface frames: 1, 2, 4 or 8.
        int rotations = 4;
        /// "flip_rows": also search the row-flipped variants (spec 13.13), without surface frames.
        bool flip_rows = true;
        /// "match_tilt_histogram": match the steepness histogram to the exemplar's (step 3).
        bool match_tilt_histogram = true;

        /// Reads the keys above; throws tdf::Error for unknown keys or bad values.
        static Options from_json(const Json& config);
    };

    /// Reads the exemplar files of `options` (if any).
    explicit ExemplarPatchMatchBackend(Options options);
    ~ExemplarPatchMatchBackend() override;

    /// Replaces the exemplars: tangent-space normal maps, 3 channels in [-1, 1] (or 4, alpha
    /// ignored). Throws tdf::Error for exemplars smaller than a patch (at the fixed
    /// exemplar_scale, or at scale 1 for "auto").
    void set_exemplars(std::vector<Image> tangent_normals) override;
    std::size_t exemplar_count() const { return m_exemplars.size(); }

    std::string name() const override { return kName; }
    bool supports(GuidanceKind kind) const override { return kind == GuidanceKind::Tactile; }
    /// Tactile requests only. `strength` is not used: the reference keeps the tactile strength
    /// constant (0.8, spec 5.5), and a projection onto the exemplar's patches has no noise level.
    GuidanceResult refine(const GuidanceRequest& request) override;

    /// Mean over the foreground pixels of `normals` (mask >= 0.5, whole window inside the image)
    /// of the squared distance from the pixel's patch to its nearest exemplar patch, found by
    /// brute force over every search variant position (at the scale of the last search, 1 by
    /// default). A statistic of how exemplar-like an image is;
    /// cost O(pixels x exemplar pixels x variants), meant for small test images.
    double mean_nearest_patch_distance(const Image& normals, const Image& mask) const;

    const Options& options() const { return m_options; }

    struct Variant;  // exemplar variant pyramid (defined in the .cpp)

private:
    /// The exemplars resampled by `factor`; rebuilt only when the factor changes (a run's
    /// requests all have the same pixels_per_texel).
    const std::vector<Image>& scaled_exemplars(float factor);
    /// The rotation (and flip) variants searched without surface frames, with the exemplars
    /// resampled by `factor`; rebuilt only when the factor changes.
    const std::vector<Variant>& search_variants(float factor);
    /// How the map lies in image `item`: the turn of its u axis in steps of a 72th of a turn (5
    /// degrees; quarter turns exact) and whether it is mirrored.
    struct Orientation {
        int step = 0;
        bool mirrored = false;
        bool operator<(const Orientation& o) const { return step != o.step ? step < o.step : mirrored < o.mirrored; }
    };
    static constexpr int kOrientationSteps = 72;
    Orientation surface_orientation(const GuidanceRequest& request, std::size_t item) const;
    /// One variant per exemplar (`scaled_exemplars(factor)`) turned and mirrored by `orientation`,
    /// and their tilt tables. Cached per orientation (patches of a run take a few dozen of them),
    /// so a refinement no longer turns the exemplars for every patch; the cache is dropped when the
    /// factor changes.
    struct OrientedVariants {
        std::vector<Variant> variants;
        std::vector<std::vector<float>> tilts;
    };
    const OrientedVariants& oriented_variants(Orientation orientation, float factor);
    /// Steps 1-4 for image `item` of the request, searched against `variants`, at the working
    /// size work_width x work_height (the image's own size, or the coarse copy's).
    Image refine_image(const GuidanceRequest& request, std::size_t item, const std::vector<Variant>& variants,
                       const std::vector<std::vector<float>>& tilts, bool use_surface, int work_width,
                       int work_height) const;
    /// The sorted tilts of all texels of `variants`, per pyramid level (the histogram matching's
    /// target; empty tables when match_tilt_histogram is off).
    std::vector<std::vector<float>> tilt_tables(const std::vector<Variant>& variants) const;
    /// Throws tdf::Error when a variant is smaller than a patch.
    void check_variants(const std::vector<Variant>& variants, float factor) const;
    /// Steps 3 of the algorithm on one (working) image: the refined unit normals. `tilts`:
    /// tilt_tables(variants).
    Image synthesize(const Image& input, const Image& mask, const std::vector<Variant>& variants,
                     const std::vector<std::vector<float>>& tilts, std::uint64_t seed,
                     std::size_t item) const;

    Options m_options;
    std::vector<Image> m_exemplars;  ///< unit tangent-space normals, as given
    std::vector<Image> m_scaled_exemplars;
    float m_scaled_factor = 0.0f;
    std::vector<Variant> m_search_variants;
    std::vector<std::vector<float>> m_search_tilts;  ///< tilt_tables(m_search_variants)
    float m_search_factor = 0.0f;
    std::map<Orientation, OrientedVariants> m_oriented;
    float m_oriented_factor = 0.0f;
};


}  // namespace tdf
