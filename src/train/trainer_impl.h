#pragma once
// What the trainer's stage files share (private to src/train/): the per-iteration buffers
// (Trainer::Batch), the phase table (Trainer::Phase) and the small per-pixel helpers. The stages
// are Trainer members, one file each, in the order of one iteration:
//   trainer.cpp                 construction, checkpoints, the iteration (step, loss_and_gradient)
//   trainer_matching.cpp        texture evaluation's matching phase: dense fit on texels
//   trainer_views.cpp           cameras, tracing, the surface at every hit
//   trainer_tactile_terms.cpp   tactile matching and guidance terms on the patches
//   trainer_visual_terms.cpp    albedo matching and visual guidance terms on the views
//   trainer_refinement.cpp      backward to the maps and the field, the optimizer step
//   trainer_export.cpp          the maps as exported, the predicted parts, the colour range
//   trainer_evaluation.cpp      held-out views and patches, the quality report
#include <tdf/train/trainer.h>

#include <tdf/core/parallel.h>
#include <tdf/render/shading.h>
#include <tdf/render/texture_gradient.h>
#include <tdf/render/trace.h>
#include <tdf/scene/view_sampler.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <vector>

namespace tdf {
namespace trainer_detail {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// Pixels per chunk in parallel per-pixel loops (writes are disjoint; only grain matters).
constexpr std::size_t kPixelGrain = 4096;

inline ViewRotation view_rotation(const Camera& c) { return {c.right, c.up, c.back}; }

inline TangentFrame frame_at(const GBuffer& g, std::size_t i) { return {g.tangent[i], g.normal[i], g.handedness[i]}; }

// The target tactile normal of a hit pixel as the training renderer builds it: sampled over the
// whole pyramid, renormalised (spec 3.1 step 5), in tangent space ...
inline Vec3f target_tangent_normal(const TrainingTarget& t, const GBuffer& g, std::size_t i) {
    return safe_normalize(sample_tactile(*t.material, g, i, -1));
}

// ... and composed with the pixel's frame, in view space.
inline Vec3f tangent_to_view(const GBuffer& g, std::size_t i, const ViewRotation& r, Vec3f tangent_normal) {
    return view_space_normal(r, compose_shading_normal(frame_at(g, i), tangent_normal));
}

inline Vec3f target_view_normal(const TrainingTarget& t, const GBuffer& g, std::size_t i, const ViewRotation& r) {
    return tangent_to_view(g, i, r, target_tangent_normal(t, g, i));
}

// A 3-channel map's value from recorded taps (the learned and target maps all have 3 channels).
inline Vec3f gather3(const MipTexture& map, const TrilinearTaps& taps) {
    float value[kMaxTextureChannels];
    map.gather(taps, value);
    return {value[0], value[1], value[2]};
}

inline void copy_into(const Image& image, float* out) { std::copy(image.values().begin(), image.values().end(), out); }

}  // namespace trainer_detail

// Buffers of one iteration. Sized on first use and reused: the hot loops allocate nothing once
// the resolutions have been seen.
struct Trainer::Batch {
    // Traced views: patches first, then visual views (the order of spec 9).
    std::vector<Camera> cameras;
    std::vector<GBuffer> gbuffers;
    std::vector<VisualView> views;
    std::vector<Vec3f> lights;                 // per visual view, for the lambertian
    std::vector<std::vector<int>> point_of;   // per gbuffer and pixel: index into points, -1 = miss
    std::vector<Vec3f> points;
    std::vector<FieldOutputs> outputs;
    std::vector<FieldOutputGrads> grads;
    FieldCache field_cache;  // the forward's encodings, reused by the backward (no second gather)
    // Three arrays of one 3-vector per pixel of the half-iteration's images (P x R x R patch
    // pixels, or B x S x S view pixels at the output size, image after image), which the two
    // halves take in turn: allocated once, written in full by each use. The patch half keeps its
    // view-space normals there (zero vectors off the surface), the view half its albedo renders
    // (while an albedo term weighs: matching, the first refinement iteration), then its lambertian
    // renders, as floats (interleaved RGB).
    std::array<std::vector<Vec3f>, 3> pixel_arrays;
    static float* floats(std::vector<Vec3f>& a) {
        static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be three packed floats");
        return reinterpret_cast<float*>(a.data());
    }
    // The pixels of the current half; the arrays never shrink, as a std::vector resized back up
    // into its capacity value-initialises the new elements on one thread (the view half has
    // five times the patch half's pixels at 224 px patches: 2 % of a refinement's samples).
    std::size_t pixel_array_count = 0;
    void size_pixel_arrays(std::size_t pixels) {
        pixel_array_count = pixels;
        for (std::vector<Vec3f>& a : pixel_arrays)
            if (a.size() < pixels) a.resize(pixels);
    }
    std::size_t pixel_array_size() const { return pixel_array_count; }
    Vec3f* patch_pred() { return pixel_arrays[0].data(); }
    Vec3f* patch_target() { return pixel_arrays[1].data(); }  // then the tactile guidance's answer
    Vec3f* patch_grad() { return pixel_arrays[2].data(); }
    float* albedo_pred() { return floats(pixel_arrays[0]); }
    float* albedo_target() { return floats(pixel_arrays[1]); }
    float* albedo_grad() { return floats(pixel_arrays[2]); }
    float* lambertian() { return floats(pixel_arrays[0]); }
    float* refined_lambertian() { return floats(pixel_arrays[1]); }  // the visual guidance's answer
    float* lambertian_grad() { return floats(pixel_arrays[2]); }
    std::vector<float> shade;  // per point: the lambertian shade of visual hits
    Image internal;            // one view at its internal (SSAA) size
    // Which view and pixel each hit came from (texture evaluation looks the maps up there).
    std::vector<std::uint32_t> hit_pixel;
    std::vector<std::uint16_t> hit_view;
    std::vector<std::size_t> chunk_hits;  // trace_views: the first hit of each chunk of pixels
    // Texture evaluation: each hit's lookup and its unnormalised normal; the map gradients.
    std::vector<Vec2f> lookup_uv;
    std::vector<float> lookup_lod;
    std::vector<Vec3f> raw_normal;
    // Per hit, what its loss compares with, read through the hit's own taps (the targets have the
    // atlas's size, so the taps are the learned maps'): patches the tactile target's normal
    // (renormalised), views the input albedo. One lookup instead of one per use.
    std::vector<Vec3f> target;
    // Per hit: the curvature of the loss with respect to the map value the hit reads, per channel
    // (the Jacobi step's denominator; texture evaluation only).
    std::vector<float> curvature;
    std::size_t patch_hit_count = 0;  // hits of the patches come first
    // The map gradients: each allocated by the first scatter into it (the normal map's after the
    // patches' guidance, the albedo's after the views'), freed by begin_map_gradients() and update().
    MipGradient albedo_gradient, normal_gradient;
    std::vector<TrilinearTaps> scatter_taps;               // scatter_map_gradients: one block's taps
    std::vector<std::array<float, 4>> scatter_values;      // ... and the values they carry
    std::vector<FieldOutputGrads> texel_grads;
    std::vector<std::uint32_t> fit_texels;  // matching phase: the texels sampled this iteration

    // Room for `pixels` hits in every per-hit array the evaluation uses (`pixels`: the traced
    // pixels of the half-iteration, an upper bound). Grown to each new largest hit count instead,
    // an array was copied and its old block left free in the heap, where later blocks fitted or
    // not depending on how the threads' allocations interleaved: the main job's peak was 582 or
    // 602 MB from run to run (2026-12-07).
    void reserve_hits(std::size_t pixels, bool texture_space) {
        if (hit_pixel.capacity() >= pixels) return;
        hit_pixel.reserve(pixels);
        hit_view.reserve(pixels);
        outputs.reserve(pixels);
        grads.reserve(pixels);
        shade.reserve(pixels);
        if (!texture_space) {
            points.reserve(pixels);
            return;
        }
        lookup_uv.reserve(pixels);
        lookup_lod.reserve(pixels);
        raw_normal.reserve(pixels);
        target.reserve(pixels);
        curvature.reserve(pixels);
    }
};

// What iteration i computes: the phase table of spec 5.1 (i is the 0-based loop index).
struct Trainer::Phase {
    int i = 0;
    bool per_pixel_albedo = false;
    float albedo_weight = 0, tactile_weight = 0;
    bool visual_guidance = false, tactile_guidance = false;
};

// The visual guidance's per-view inputs beside the lambertian renders, at the output size.
struct Trainer::GuidanceImages {
    std::vector<Image> controls;  // the learned view-space normals as the backend's control image
    std::vector<Image> masks;     // coverage
    std::vector<Image> surfaces;  // the mesh's own view-space normals (no relief)
    std::vector<Image> references;  // the input's lambertian under the same light (relief anchor)
    std::vector<Image> lambertians;  // the learned maps' lambertian renders (what guidance refines)
};

}  // namespace tdf
