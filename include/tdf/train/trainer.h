#pragma once
/// The optimization loop of `tdf optimize` (spec 9). One iteration is a short sequence of stages:
/// sample cameras, trace them with Embree, evaluate the surface at every hit, form the matching and
/// guidance losses, back-propagate by hand, take one Adam step.
///
/// Two ways to evaluate the surface (RunConfig::evaluation):
///  - Texture (default): the learned albedo and normal maps over the UV atlas (LearnedMaps: hash
///    grid at each texel's surface point plus a per-texel residual) are what every hit samples,
///    trilinearly with the renderer's LOD, and gradients go back through the adjoint of that
///    sampling to the texels. The matching phase fits the grid to the targets laid over the atlas
///    on random texels (no rendering: the targets are known in texture space), then the residual
///    takes the rest, so the maps equal the targets when refinement starts.
///  - Pixel (schedule=reference): the field at every ray hit, as the reference (spec 4.3).
///
/// Reproducibility: iteration i draws all its randomness from Rng::stream(seed, i), and every
/// reduction is chunked in a fixed order, so a run gives the same field on any thread count
/// and a resumed run continues exactly where the interrupted one stopped.
#include <tdf/core/rng.h>
#include <tdf/field/texture_field.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/optim/adam.h>
#include <tdf/optim/checkpoint.h>
#include <tdf/render/gbuffer.h>
#include <tdf/render/material_sampling.h>
#include <tdf/render/renderer.h>
#include <tdf/scene/camera.h>
#include <tdf/scene/embree_scene.h>
#include <tdf/train/albedo_range.h>
#include <tdf/train/loss_log.h>
#include <tdf/train/learned_maps.h>
#include <tdf/train/run_config.h>
#include <tdf/train/tactile_seam_blend.h>
#include <tdf/train/texel_atlas.h>
#include <tdf/train/texture_bake.h>

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
    std::string prompt;                     ///< visual guidance text (spec 5.7)
    /// Multi-part scenes (docs/multi-part-textures.md; texture evaluation only, the trainer
    /// refuses pixel evaluation with parts). All three are set together or not at all.
    /// The composed tactile target over the atlas (texture_size x texture_size, 3 channels, unit
    /// normals in [-1, 1], compose_part_target): used instead of tactile_target(); one normal
    /// map holds all parts.
    const Image* tactile_target_override = nullptr;
    /// Per atlas texel (i * size + j), the ground-truth part, -1 where no face covers the texel
    /// (PartSegmentation::texel_part). The label head (PartLabelHead, one logit per part) is
    /// trained on them by softmax cross-entropy during the matching phase; its prediction gates
    /// the tactile terms of refinement per part (PartGate).
    const std::vector<int>* texel_parts = nullptr;
    std::vector<std::string> part_names;
};

/// How many patch pixels one texel of the tactile map spans on the surface: the patch window
/// (patch_resolution pixels over 2 patch_half_extent units) against the map's mean texel size on
/// the atlas (sqrt(3-D area / UV area) over sqrt(width x height) x uv_scale texels per UV unit).
/// 0 without a tactile map or UVs. Tactile guidance requests carry it (GuidanceRequest).
float patch_pixels_per_texel(const TrainingTarget& target, const RunConfig& config);

/// Held-out quality after training (docs/measurements.md).
struct QualityReport {
    double albedo_psnr_foreground = 0;  ///< dB over covered pixels of the held-out views
    double albedo_psnr_full = 0;        ///< dB over whole images, white background included
    double albedo_max_error = 0;        ///< largest per-channel absolute error on covered pixels
    double tactile_mean_cosine = 0;     ///< learned vs target view-space normals, patch hits
    /// Colour-geometry alignment of the learned albedo and normals (colour_geometry_correlation,
    /// mean over the held-out views): what visual guidance raises (issue 6).
    double colour_geometry_correlation = 0;
    /// The same measure on what the run added (learned minus input albedo, issue 29) against the
    /// relief's own curvature (view normals minus the surface's, as relief_shading takes it):
    /// whether the colour the refinement put in follows the relief, whatever prints the input
    /// carries and however curved the mesh is. 0 when nothing was added.
    double added_colour_geometry_correlation = 0;
    /// How exemplar-like the learned relief is, whatever its position (what tactile guidance
    /// lowers, issue 6): L1 distance between the tilt histograms (relief_statistics.h) of the
    /// learned tangent-space normals at the held-out patch hits and of the tactile map's texels.
    /// 0 without a tactile map.
    double tactile_tilt_distance = 0;
    /// The same for the target normals at those hits: the floor that sampling leaves.
    double target_tilt_distance = 0;
    /// Seams (issue 10 goal 4): mean colour / view-space normal jump between neighbouring pixels
    /// across UV seams (chart boundaries of the mesh) over the jump inside charts, on the
    /// held-out views (SeamJump).
    double seam_jump_ratio_albedo = 0;
    double seam_jump_ratio_normal = 0;
    /// The same measure of the input's own albedo (its texture through its UVs) on those views:
    /// what the asset had before training.
    double input_seam_jump_ratio_albedo = 0;
    std::size_t seam_pairs = 0;
    /// The same three ratios on the turntable's views (the measure: a turntable sees
    /// every meridian, so a seam such as a sphere's u = 0/1 falls in it), and their seam pairs.
    double turntable_seam_jump_ratio_albedo = 0;
    double turntable_seam_jump_ratio_normal = 0;
    double turntable_input_seam_jump_ratio_albedo = 0;
    double turntable_input_seam_jump_ratio_normal = 0;  ///< the tactile target laid over the atlas
    std::size_t turntable_seam_pairs = 0;
    /// Jumps across UV cones (a pole's fan, SeamJump) over the interior, learned and input: reported
    /// apart from seams because the input's own texture changes with the UV direction there.
    double turntable_cone_jump_ratio_albedo = 0;
    double turntable_input_cone_jump_ratio_albedo = 0;
    std::size_t turntable_cone_pairs = 0;
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

/// Per-stage seconds of the iterations so far (docs/measurements.md).
struct StageTimes {
    double tracing = 0, field_forward = 0, losses = 0, guidance = 0, field_backward = 0, adam = 0;
    double matching = 0;  ///< texture evaluation: dense fit iterations (no rendering)
    Json to_json(int iterations) const;
};

class PartLabelHead;
class PartGate;
struct PartGuidance;

class Trainer {
public:
    /// Builds the field over the mesh's bounding box, initialised from `seed`.
    Trainer(const TrainingTarget& target, const RunConfig& config, std::uint64_t seed);
    ~Trainer();

    /// Guidance backends for the refinement phase; nullptr disables a term (the run then logs
    /// that it refines with the matching terms only).
    void set_guidance(std::unique_ptr<GuidanceBackend> visual, std::unique_ptr<GuidanceBackend> tactile);
    /// Multi-part: each part's tactile settings and guidance backend (one per part, in part
    /// order, names as TrainingTarget::part_names). Without this call every part uses the run's
    /// weights and no part has tactile guidance; the single tactile backend of set_guidance() is
    /// not used with parts.
    void set_part_guidance(std::vector<PartGuidance> parts);
    /// Writes every guidance request and result as PNG frames under `folder` (spec 8.2).
    void save_guidance_frames_to(const std::string& folder) { m_frames_folder = folder; }

    /// Runs iteration `iteration()` and advances. Throws tdf::Error when a loss term is not
    /// finite (naming the term); the field is then left as it was before the step.
    LossRecord step();
    int iteration() const { return m_iteration; }
    /// Frees the per-iteration buffers (views, hits, map gradients) once training is over, so
    /// that exporting and evaluating do not add to their peak; the next step re-allocates them.
    void release_training_buffers();
    /// Once the last iteration has run: frees the per-iteration buffers and what only further
    /// iterations read (texture evaluation: the residual and its optimizer state, the field's
    /// outputs at the texels, the colour bounds: 80 bytes a texel, 1.3 GB at 4096^2 maps). The
    /// maps stay for export_maps(), evaluate_held_out() and the measures; step(), parameters()
    /// and checkpoints refuse from then on.
    void finish_training();
    /// Between iterations, for a memory-heavy step that reads only export_maps() and the targets'
    /// level 0 (the export after matching): frees the per-iteration buffers and what the field,
    /// the input and level 0 give back bit for bit (texture evaluation: the field's outputs at the
    /// texels, the colour bounds, the mip levels above 0 of the maps and targets: 1.5 GB at 4096^2
    /// maps). step() and
    /// evaluate_held_out() refuse until restore_derived_state() has rebuilt them. After
    /// finish_training() only the mip levels are released and rebuilt (the final export).
    void release_derived_state();
    void restore_derived_state();

    /// Iteration `i`'s losses and their gradient with respect to parameters(), without changing
    /// anything (for finite-difference checks of the whole trainer). Guidance targets count as
    /// constants, as in step(). Texture evaluation: `i` must be past the matching phase.
    LossRecord loss_and_gradient(int i);
    /// The gradient from the last loss_and_gradient() (or step()), laid out like parameters().
    /// With the Jacobi residual step (the default), only after loss_and_gradient(): step() has
    /// consumed the map gradients the residual's is derived from.
    std::vector<float> gradient() const;
    /// Replaces every trained value (laid out like parameters()) and refreshes the maps.
    void set_parameters(const std::vector<float>& parameters);

    TextureField& field() { return *m_field; }
    const TextureField& field() const { return *m_field; }
    /// Every trained value: the field's parameters, then (texture evaluation) the residual, then
    /// (multi-part) the label head's.
    std::vector<float> parameters() const;
    /// The optimizer state matching parameters() (moments concatenated the same way).
    AdamState optimizer_state() const;
    /// parameters() and optimizer_state() as pieces of the arrays that hold them, for streaming
    /// a checkpoint without copies (valid until the next step).
    CheckpointPieces checkpoint_pieces() const;
    /// Restores a checkpoint taken after `iteration` iterations (parameters() / optimizer_state()).
    void restore(int iteration, const std::vector<float>& parameters, const AdamState& adam);

    /// The maps as they are now, ready to export: the learned maps themselves (texture
    /// evaluation) or a bake of the field (pixel evaluation).
    BakedMaps export_maps() const;
    /// The texture-space table and targets (texture evaluation only; nullptr otherwise).
    const TexelAtlas* texel_atlas() const { return m_atlas.get(); }
    const Image& albedo_target() const { return m_albedo_target_texture.level(0); }
    const Image& tactile_target() const { return m_tactile_target_texture.level(0); }
    /// How far `albedo` (size x size RGB, e.g. export_maps().albedo) leaves the input albedo's
    /// local range (albedo_range.h, radius kRangeMeasureRadius, limit kRangeMeasureLimit), over
    /// the covered texels (texture evaluation only).
    RangeExcess albedo_range_excess(const Image& albedo) const;
    /// Per texel its UV chart, -1 in the gutter (texture evaluation only; albedo_range.h).
    const std::vector<int>& texel_charts() const { return m_texel_charts; }
    /// What cross_fade_tactile_seams did to the tactile target (zeros per pixel or with a band of 0).
    const SeamBlendStats& tactile_seam_blend() const { return m_seam_blend; }
    /// Multi-part: the part the label head predicts (argmax of its logits at each covered
    /// texel's surface point), -1 at uncovered texels; size x size. Empty without parts.
    std::vector<int> predicted_texel_parts() const;
    /// Whether the label head is trained (multi-part).
    bool trains_labels() const { return m_label_head != nullptr; }
    /// Multi-part: the gate of the tactile terms (its labels are set when refinement starts).
    const PartGate* part_gate() const { return m_part_gate.get(); }

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
    struct Phase;  // what iteration i computes (spec 5.1)
    struct GuidanceImages;  // visual guidance inputs per view (trainer_impl.h)

    // The stages of one iteration, in order (each file's header says what it reads and writes).
    // trainer_matching.cpp
    LossRecord fit_maps(int i);  // texture evaluation, matching phase: dense fit, no rendering
    // trainer_views.cpp
    void sample_cameras(Rng& rng);
    /// Trace, surface, loss terms (and, texture evaluation, the scatter into the map gradients)
    /// for the cameras [first, last): patches come first, then visual views.
    void run_views(const Phase& phase, std::size_t first, std::size_t last, LossRecord& record);
    void trace_views(std::size_t first, std::size_t last);
    void evaluate_surface(bool with_view_normals);
    // trainer_tactile_terms.cpp
    void tactile_terms(const Phase& phase, LossRecord& record);
    // trainer_visual_terms.cpp: the views' renders, the albedo term, visual guidance, backward.
    void visual_terms(const Phase& phase, LossRecord& record);
    void render_visual_views(bool albedo_terms, bool visual_guidance, GuidanceImages& guidance_images);
    void visual_guidance_terms(const Phase& phase, GuidanceImages guidance_images, LossRecord& record);
    void add_view_gradient(const float* grad, bool lambertian);
    void set_view_curvature(const Phase& phase);
    // trainer_refinement.cpp
    void begin_map_gradients();
    void reset_map_gradient(int map);
    void scatter_map_gradients();
    /// Lets the visual views reuse the patches' G-buffers and back (texture evaluation).
    void swap_patch_and_view_buffers();
    void backward(int i);
    void update(int i);
    Phase phase_of(int i) const;

    /// Texture evaluation: makes the maps equal the targets (r = target - grid) once the grid fit
    /// is over, and refreshes them after every update.
    void prepare_maps();
    /// Texture evaluation: the maps' colour bound from the input albedo (issue 29), none when
    /// optimize.albedo_range_radius is 0.
    void set_albedo_bounds();
    /// The surface at pixels of a traced view: the field at the hits (pixel evaluation) or the
    /// learned maps sampled there (texture evaluation), in pixel order of the hits.
    void evaluate_hits(const GBuffer& g, std::vector<FieldOutputs>& outputs) const;
    /// Traces `camera` into `g` and evaluates the surface at its hits, in pixel order.
    void trace_and_evaluate(const Camera& camera, GBuffer& g, std::vector<FieldOutputs>& outputs) const;
    /// evaluate_held_out's patch measures (tactile cosine, tilt distances, patch count).
    void measure_held_out_patches(QualityReport& report) const;
    /// Multi-part: the matching phase's label cross-entropy on the fit texels (gradient into the
    /// grid's part of m_gradient and the head's own), its Adam step; the gated tactile terms.
    double fit_labels(std::size_t n);
    void gated_tactile_terms(const Phase& phase, LossRecord& record);
    bool texture_space() const { return m_config.evaluation == FieldEvaluation::Texture; }

    const TrainingTarget m_target;
    const RunConfig m_config;
    const std::uint64_t m_seed;
    const float m_patch_pixels_per_texel;
    std::unique_ptr<TextureField> m_field;
    std::unique_ptr<Adam> m_adam;
    // Texture evaluation.
    std::unique_ptr<TexelAtlas> m_atlas;
    std::unique_ptr<LearnedMaps> m_maps;
    std::vector<int> m_texel_charts;  ///< per texel its UV chart, -1 in the gutter (albedo_range.h)
    SeamBlendStats m_seam_blend;
    // The input albedo and the tactile target over the atlas, as renders sample them; their level
    // 0 is the per-texel target of the matching phase (held once: albedo_target(), tactile_target()).
    MipTexture m_albedo_target_texture;
    MipTexture m_tactile_target_texture;
    std::unique_ptr<Adam> m_residual_adam;
    std::vector<float> m_residual_gradient;  // Adam's residual step only
    bool m_map_gradients_unstepped = false;  // Batch's map gradients are backward()'s, not yet stepped on
    bool m_maps_ready = false;
    bool m_training_finished = false;  // finish_training() ran
    bool m_derived_released = false;   // release_derived_state() ran, restore_derived_state() not yet
    // Multi-part.
    std::unique_ptr<PartLabelHead> m_label_head;
    std::unique_ptr<Adam> m_label_adam;
    std::vector<float> m_label_gradient;
    std::unique_ptr<PartGate> m_part_gate;
    bool m_gate_labels_stale = true;  // the head or the grid changed since the gate's labels
    std::unique_ptr<GuidanceBackend> m_visual_guidance;
    std::unique_ptr<GuidanceBackend> m_tactile_guidance;
    std::unique_ptr<Batch> m_batch;
    std::vector<float> m_gradient;
    std::string m_frames_folder;
    int m_iteration = 0;
    StageTimes m_times;
};

}  // namespace tdf
