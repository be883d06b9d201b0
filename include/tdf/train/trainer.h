#pragma once
/// The optimization loop of `tdf optimize` (spec 9): per iteration, trace tactile patch views and
/// visual views with Embree, evaluate the texture field at every hit, form the matching and
/// guidance losses, back-propagate by hand into the field and take one Adam step.
///
/// Reproducibility: iteration i draws all its randomness from Rng::stream(seed, i), and every
/// reduction is chunked in a fixed order, so a run gives the same field on any thread count
/// and a resumed run continues exactly where the interrupted one stopped.
#include <tdf/field/texture_field.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/optim/adam.h>
#include <tdf/render/gbuffer.h>
#include <tdf/render/material_sampling.h>
#include <tdf/render/renderer.h>
#include <tdf/scene/camera.h>
#include <tdf/scene/embree_scene.h>
#include <tdf/train/loss_log.h>
#include <tdf/train/run_config.h>

#include <memory>
#include <string>
#include <vector>

namespace tdf {

/// What the field is trained to reproduce: the base mesh's colour and the tactile map laid over
/// its UV atlas. Borrowed: everything must outlive the Trainer.
struct TrainingTarget {
    const TriangleMesh* mesh = nullptr;     ///< with UVs, normals and tangents
    const EmbreeScene* scene = nullptr;     ///< built from `mesh`
    const SurfaceMaterial* material = nullptr;  ///< base albedo source + tactile map (decoded)
    TactileLayoutTransform tactile_layout;  ///< how the tactile map repeats over the atlas
    std::string prompt;                     ///< visual guidance text (spec 5.7)
};

/// The UV scale that lays a tactile map at its physical size (TactileLayout::Physical): the
/// atlas's mean surface size per UV unit, sqrt(3-D area / UV area) x mm_per_unit, divided by
/// the map's width in millimetres. Throws tdf::Error when the mesh has no UV area.
float physical_tactile_uv_scale(const TriangleMesh& mesh, float mm_per_unit, int map_width_pixels,
                                float mm_per_pixel);

/// How many patch pixels one texel of the tactile map spans on the surface: the patch window
/// (patch_resolution pixels over 2 patch_half_extent units) against the map's mean texel size on
/// the atlas (sqrt(3-D area / UV area) over sqrt(width x height) x uv_scale texels per UV unit).
/// 0 without a tactile map or UVs. Tactile guidance requests carry it (GuidanceRequest).
float patch_pixels_per_texel(const TrainingTarget& target, const RunConfig& config);

/// Held-out quality after training (README "Measured").
struct QualityReport {
    double albedo_psnr_foreground = 0;  ///< dB over covered pixels of the held-out views
    double albedo_psnr_full = 0;        ///< dB over whole images, white background included
    double albedo_max_error = 0;        ///< largest per-channel absolute error on covered pixels
    double tactile_mean_cosine = 0;     ///< learned vs target view-space normals, patch hits
    /// Colour-geometry alignment of the learned albedo and normals (colour_geometry_correlation,
    /// mean over the held-out views): what visual guidance raises (issue 6).
    double colour_geometry_correlation = 0;
    /// How exemplar-like the learned relief is, whatever its position (what tactile guidance
    /// lowers, issue 6): L1 distance between the tilt histograms (relief_statistics.h) of the
    /// learned tangent-space normals at the held-out patch hits and of the tactile map's texels.
    /// 0 without a tactile map.
    double tactile_tilt_distance = 0;
    /// The same for the target normals at those hits: the floor that sampling leaves.
    double target_tilt_distance = 0;
    int views = 0;
    int patches = 0;
    Json to_json() const;
};

/// The learned field seen from one camera: albedo composited on white, view-space shading
/// normals (zero off the surface) and the coverage mask, all camera.width x camera.height.
struct LearnedImages {
    Image albedo;
    Image view_normals;
    Image mask;
};

/// Per-stage seconds of the iterations so far (README "Measured").
struct StageTimes {
    double tracing = 0, field_forward = 0, losses = 0, guidance = 0, field_backward = 0, adam = 0;
    Json to_json(int iterations) const;
};

class Trainer {
public:
    /// Builds the field over the mesh's bounding box, initialised from `seed`.
    Trainer(const TrainingTarget& target, const RunConfig& config, std::uint64_t seed);
    ~Trainer();

    /// Guidance backends for the refinement phase; nullptr disables a term (the run then logs
    /// that it refines with the matching terms only).
    void set_guidance(std::unique_ptr<GuidanceBackend> visual, std::unique_ptr<GuidanceBackend> tactile);
    /// Writes every guidance request and result as PNG frames under `folder` (spec 8.2).
    void save_guidance_frames_to(const std::string& folder) { m_frames_folder = folder; }

    /// Runs iteration `iteration()` and advances. Throws tdf::Error when a loss term is not
    /// finite (naming the term); the field is then left as it was before the step.
    LossRecord step();
    int iteration() const { return m_iteration; }

    TextureField& field() { return *m_field; }
    const TextureField& field() const { return *m_field; }
    const Adam& optimizer() const { return *m_adam; }
    /// Restores a checkpoint taken after `iteration` iterations.
    void restore(int iteration, const std::vector<float>& parameters, const AdamState& adam);

    /// Albedo PSNR and tactile cosine on views and patches drawn from a stream no training
    /// iteration uses.
    QualityReport evaluate_held_out() const;
    /// The k-th held-out visual view (no SSAA) and tactile patch camera.
    Camera held_out_view(int k) const;
    Camera held_out_patch(int k) const;
    /// Renders the current field from `camera` (spec 3.1-3.5 training shading).
    LearnedImages render_learned(const Camera& camera) const;
    const StageTimes& stage_times() const { return m_times; }
    float pixels_per_texel() const { return m_patch_pixels_per_texel; }

private:
    struct Batch;  // per-iteration buffers, allocated once (trainer.cpp)

    /// Traces `camera` into `g` and evaluates the field at its hits, in pixel order.
    void trace_and_evaluate(const Camera& camera, GBuffer& g, std::vector<FieldOutputs>& outputs) const;

    const TrainingTarget m_target;
    const RunConfig m_config;
    const std::uint64_t m_seed;
    const float m_patch_pixels_per_texel;
    std::unique_ptr<TextureField> m_field;
    std::unique_ptr<Adam> m_adam;
    std::unique_ptr<GuidanceBackend> m_visual_guidance;
    std::unique_ptr<GuidanceBackend> m_tactile_guidance;
    std::unique_ptr<Batch> m_batch;
    std::vector<float> m_gradient;
    std::string m_frames_folder;
    int m_iteration = 0;
    StageTimes m_times;
};

}  // namespace tdf
