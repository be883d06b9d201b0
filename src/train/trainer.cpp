#include <tdf/train/trainer.h>

#include <tdf/train/asset_export.h>
#include <tdf/train/part_gating.h>
#include <tdf/train/part_label_head.h>
#include <tdf/train/tactile_seam_blend.h>
#include <tdf/train/texture_fidelity.h>

#include <tdf/atlas/uv_metrics.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/guidance/guidance_frames.h>
#include <tdf/guidance/relief_shading.h>
#include <tdf/guidance/schedule.h>
#include <tdf/loss/image_loss.h>
#include <tdf/render/shading.h>
#include <tdf/loss/tactile_loss.h>
#include <tdf/core/image_ops.h>
#include <tdf/parts/part_target.h>
#include <tdf/render/shading.h>
#include <tdf/render/texture_gradient.h>
#include <tdf/render/trace.h>
#include <tdf/scene/view_sampler.h>
#include <tdf/tactile/relief_statistics.h>

#include <chrono>
#include <cmath>

namespace tdf {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// Held-out views and patches come from streams far away from any iteration index.
constexpr std::uint64_t kHeldOutStream = 0x68656c646f7574ULL;
// Pixels per chunk in parallel per-pixel loops (writes are disjoint; only grain matters).
constexpr std::size_t kPixelGrain = 4096;
// Weight of the label cross-entropy (multi-part): the reference's lambda_label_field.
constexpr float kLabelWeight = 1.0f;

ViewRotation view_rotation(const Camera& c) { return {c.right, c.up, c.back}; }

TangentFrame frame_at(const GBuffer& g, std::size_t i) { return {g.tangent[i], g.normal[i], g.handedness[i]}; }

// The target tactile normal of a hit pixel as the training renderer builds it: sampled over the
// whole pyramid, renormalised (spec 3.1 step 5), in tangent space ...
Vec3f target_tangent_normal(const TrainingTarget& t, const GBuffer& g, std::size_t i) {
    return safe_normalize(sample_tactile(*t.material, g, i, -1));
}

// ... and composed with the pixel's frame, in view space.
Vec3f tangent_to_view(const GBuffer& g, std::size_t i, const ViewRotation& r, Vec3f tangent_normal) {
    return view_space_normal(r, compose_shading_normal(frame_at(g, i), tangent_normal));
}

Vec3f target_view_normal(const TrainingTarget& t, const GBuffer& g, std::size_t i, const ViewRotation& r) {
    return tangent_to_view(g, i, r, target_tangent_normal(t, g, i));
}

// A 3-channel map's value from recorded taps (the learned and target maps all have 3 channels).
Vec3f gather3(const MipTexture& map, const TrilinearTaps& taps) {
    float value[kMaxTextureChannels];
    map.gather(taps, value);
    return {value[0], value[1], value[2]};
}

void copy_into(const Image& image, float* out) { std::copy(image.values().begin(), image.values().end(), out); }

// Appends one patch to a tactile guidance request: its rendered view-space normals `pred`, its
// coverage (times `weight` per pixel when given: a part's mask) and its surface frames.
void add_patch_to_request(GuidanceRequest& request, const GBuffer& g, const Camera& camera, const Vec3f* pred,
                          const float* weight) {
    const int w = g.width, h = g.height;
    const ViewRotation rot = view_rotation(camera);
    Image normals(w, h, 3), mask(w, h, 1), surface_normals(w, h, 3), surface_tangents(w, h, 4);
    for (std::size_t p = 0; p < g.pixel_count(); ++p) {
        std::copy(&pred[p].x, &pred[p].x + 3, normals.data() + 3 * p);
        mask.data()[p] = weight ? g.mask[p] * weight[p] : g.mask[p];
        if (g.mask[p] <= 0.0f) continue;
        const Vec3f normal = view_space_normal(rot, g.normal[p]), tangent = view_space_normal(rot, g.tangent[p]);
        std::copy(&normal.x, &normal.x + 3, surface_normals.data() + 3 * p);
        std::copy(&tangent.x, &tangent.x + 3, surface_tangents.data() + 4 * p);
        surface_tangents.data()[4 * p + 3] = g.handedness[p];
    }
    request.images.push_back(std::move(normals));
    request.masks.push_back(std::move(mask));
    request.surface_normals.push_back(std::move(surface_normals));
    request.surface_tangents.push_back(std::move(surface_tangents));
}

}  // namespace

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
    // Patch view-space normals, P x R x R, zero vectors off the surface.
    std::vector<Vec3f> patch_pred, patch_target, patch_grad;
    // Visual images at the output size, B x S x S x 3 (interleaved, image after image).
    std::vector<float> albedo_pred, albedo_target, albedo_grad, lambertian, lambertian_grad;
    std::vector<float> lambertian_target;  // the input's lambertian under the same light (relief anchor)
    std::vector<float> shade;  // per point: the lambertian shade of visual hits
    Image internal;            // one view at its internal (SSAA) size
    // Which view and pixel each hit came from (texture evaluation looks the maps up there).
    std::vector<std::uint32_t> hit_pixel;
    std::vector<std::uint16_t> hit_view;
    // Texture evaluation: each hit's lookup and its unnormalised normal; the map gradients.
    std::vector<Vec2f> lookup_uv;
    std::vector<float> lookup_lod;
    std::vector<Vec3f> raw_normal;
    // Per hit: the curvature of the loss with respect to the map value the hit reads, per channel
    // (the Jacobi step's denominator; texture evaluation only).
    std::vector<float> curvature;
    std::size_t patch_hit_count = 0;  // hits of the patches come first
    MipGradient albedo_gradient, normal_gradient;
    std::vector<FieldOutputGrads> texel_grads;
    std::vector<std::uint32_t> fit_texels;  // matching phase: the texels sampled this iteration
};

float patch_pixels_per_texel(const TrainingTarget& target, const RunConfig& config) {
    const MipTexture* map = target.material->tactile;
    if (!map || map->empty() || !target.mesh->has_uvs()) return 0.0f;
    const double texels_per_uv_unit =
        std::sqrt(double(map->width()) * double(map->height())) * target.material->tactile_layout.uv_scale;
    const double units_per_texel = mesh_units_per_uv_unit(*target.mesh) / texels_per_uv_unit;
    const double pixels_per_unit = double(config.patch_resolution) / (2.0 * double(config.patch_half_extent));
    return float(units_per_texel * pixels_per_unit);
}

Trainer::Trainer(const TrainingTarget& target, const RunConfig& config, std::uint64_t seed)
    : m_target(target),
      m_config(config),
      m_seed(seed),
      m_patch_pixels_per_texel(patch_pixels_per_texel(target, config)),
      m_batch(std::make_unique<Batch>()) {
    TDF_CHECK(target.mesh && target.scene && target.material);
    const Bounds3 bounds = compute_bounds(*target.mesh);
    FieldConfig field_config;
    field_config.input = config.field_raw_coordinates ? FieldInput::RawWrapped : FieldInput::BoundingBox;
    field_config.grid.log2_table_size = config.table_log2;
    const bool parts = target.texel_parts != nullptr;
    if (parts) {
        if (!texture_space())
            throw_error("multi-part scenes need field.evaluation=texture (the part labels and the composed tactile "
                        "target live on the UV atlas); pixel evaluation with parts is not supported");
        TDF_CHECK(target.tactile_target_override && target.part_names.size() >= 2);
    }
    m_field = std::make_unique<TextureField>(field_config, FieldDomain{bounds.lower, bounds.upper}, seed);
    AdamHyperparams hyper;
    hyper.learning_rate = config.learning_rate;
    m_adam = std::make_unique<Adam>(m_field->parameter_count(), hyper);
    if (parts) {
        // One logit per part (the field's own label rows are fixed at 2 and stay off).
        m_label_head = std::make_unique<PartLabelHead>(int(target.part_names.size()), m_field->feature_count(), seed);
        m_label_adam = std::make_unique<Adam>(m_label_head->parameters().size(), hyper);
        std::vector<PartGuidance> gates(target.part_names.size());
        for (std::size_t k = 0; k < gates.size(); ++k) gates[k].name = target.part_names[k];
        m_part_gate = std::make_unique<PartGate>(config.texture_size, std::move(gates));
    }
    m_gradient.assign(m_field->parameter_count(), 0.0f);
    if (texture_space()) {
        if (!target.mesh->has_uvs())
            throw_error("{}: field.evaluation=texture needs a UV atlas (load the mesh with UVs or unwrap it)",
                        target.mesh->source_path);
        m_atlas = std::make_unique<TexelAtlas>(TexelAtlas::build(*target.mesh, config.texture_size));
        m_albedo_target = tdf::albedo_target(*m_atlas, *target.material, *target.mesh);
        if (parts) {
            const int size = config.texture_size;
            if (target.tactile_target_override->width() != size || target.tactile_target_override->height() != size ||
                target.tactile_target_override->channels() != 3 ||
                target.texel_parts->size() != std::size_t(size) * std::size_t(size))
                throw_error("multi-part: the composed tactile target and the part labels must be {0}x{0} "
                            "(optimize.texture_size)", size);
            m_tactile_target = *target.tactile_target_override;
        } else {
            m_tactile_target = tdf::tactile_target(*m_atlas, *target.material);
            m_seam_blend = cross_fade_tactile_seams(m_tactile_target, *m_atlas, *target.mesh, *target.material,
                                                    config.tactile_seam_band);
        }
        m_albedo_target_texture = MipTexture(m_albedo_target);
        m_tactile_target_texture = MipTexture(m_tactile_target);
        m_maps = std::make_unique<LearnedMaps>(*m_atlas);
        m_texel_charts = atlas_texel_charts(*m_atlas, *target.mesh);
        if (config.albedo_range_radius > 0) {
            // The refinement's colour bound (issue 29): the input's local range, widened.
            ColourRange bound = local_colour_range(m_albedo_target, m_texel_charts, config.albedo_range_radius);
            for (float& v : bound.low.values()) v -= config.albedo_range_darken;
            for (float& v : bound.high.values()) v += config.albedo_range_lighten;
            m_maps->set_albedo_bounds(std::move(bound.low), std::move(bound.high));
        }
        // Adam state for the residual only when it is Adam's to update (the Jacobi step has none).
        if (config.residual_optimizer == "adam")
            m_residual_adam = std::make_unique<Adam>(m_maps->residual().size(), hyper);
        log_verbose("texture-space optimizer: {} of {} texels covered ({:.1f} %)", m_atlas->covered_count(),
                    m_atlas->texel_count(), 100.0 * double(m_atlas->covered_count()) / double(m_atlas->texel_count()));
        if (config.init_iterations == 0) prepare_maps();
    }
}

Trainer::~Trainer() = default;

void Trainer::set_part_guidance(std::vector<PartGuidance> parts) {
    TDF_CHECK(m_part_gate && parts.size() == std::size_t(m_part_gate->part_count()));
    for (const PartGuidance& p : parts)
        if (p.backend && !p.backend->supports(GuidanceKind::Tactile))
            throw_error("part '{}': guidance backend '{}' cannot do tactile guidance", p.name, p.backend->name());
    m_part_gate->set_parts(std::move(parts));
}

void Trainer::set_guidance(std::unique_ptr<GuidanceBackend> visual, std::unique_ptr<GuidanceBackend> tactile) {
    if (visual && !visual->supports(GuidanceKind::Visual))
        throw_error("guidance backend '{}' cannot do visual guidance", visual->name());
    if (tactile && !tactile->supports(GuidanceKind::Tactile))
        throw_error("guidance backend '{}' cannot do tactile guidance", tactile->name());
    m_visual_guidance = std::move(visual);
    m_tactile_guidance = std::move(tactile);
}

namespace {
std::vector<float> concatenate(const std::vector<FloatRange>& ranges) {
    std::vector<float> all;
    for (const FloatRange& r : ranges) {
        if (r.data) all.insert(all.end(), r.data, r.data + r.size);
        else all.resize(all.size() + r.size, 0.0f);
    }
    return all;
}
}  // namespace

std::vector<float> Trainer::parameters() const { return concatenate(checkpoint_pieces().parameters); }

AdamState Trainer::optimizer_state() const {
    const CheckpointPieces pieces = checkpoint_pieces();
    return AdamState{concatenate(pieces.m), concatenate(pieces.v), pieces.step};
}

// The field, then (texture evaluation) the residual, then (multi-part) the label head.
CheckpointPieces Trainer::checkpoint_pieces() const {
    const AdamState& field = m_adam->state();
    CheckpointPieces pieces;
    pieces.parameters = {{m_field->parameters().data(), m_field->parameters().size()}};
    pieces.m = {{field.m.data(), field.m.size()}};
    pieces.v = {{field.v.data(), field.v.size()}};
    pieces.step = field.step;
    if (m_maps) {
        const std::vector<float>& residual = m_maps->residual();
        pieces.parameters.push_back({residual.data(), residual.size()});
        // The Jacobi step keeps no moments; zeros keep the checkpoint's layout (one moment per
        // parameter) the same for both residual optimizers.
        const AdamState* r = m_residual_adam ? &m_residual_adam->state() : nullptr;
        pieces.m.push_back({r ? r->m.data() : nullptr, residual.size()});
        pieces.v.push_back({r ? r->v.data() : nullptr, residual.size()});
    }
    if (m_label_head) {
        const std::vector<float>& head = m_label_head->parameters();
        const AdamState& l = m_label_adam->state();
        pieces.parameters.push_back({head.data(), head.size()});
        pieces.m.push_back({l.m.data(), l.m.size()});
        pieces.v.push_back({l.v.data(), l.v.size()});
    }
    return pieces;
}

void Trainer::restore(int iteration, const std::vector<float>& parameters, const AdamState& adam) {
    const std::size_t field_count = m_field->parameter_count();
    const std::size_t residual_count = m_maps ? m_maps->residual().size() : 0;
    const std::size_t label_count = m_label_head ? m_label_head->parameters().size() : 0;
    const std::size_t moments = field_count + residual_count + label_count;
    if (parameters.size() != moments || adam.m.size() != moments || adam.v.size() != moments)
        throw_error("checkpoint has {} parameters, this configuration needs {}", parameters.size(), moments);
    const auto split = [&](const std::vector<float>& all, std::size_t begin, std::size_t count) {
        return std::vector<float>(all.begin() + std::ptrdiff_t(begin), all.begin() + std::ptrdiff_t(begin + count));
    };
    m_field->parameters() = split(parameters, 0, field_count);
    m_adam->restore(AdamState{split(adam.m, 0, field_count), split(adam.v, 0, field_count), adam.step});
    m_iteration = iteration;
    if (m_label_head) {
        // The head takes one step per matching iteration.
        const std::size_t first = field_count + residual_count;
        m_label_head->parameters() = split(parameters, first, label_count);
        m_label_adam->restore(AdamState{split(adam.m, first, label_count), split(adam.v, first, label_count),
                                        std::min(iteration, m_config.init_iterations)});
        m_gate_labels_stale = true;
    }
    if (m_maps) {
        m_maps->residual() = split(parameters, field_count, residual_count);
        // The residual takes one step per refinement iteration, from the end of matching on.
        const std::int64_t residual_steps = std::max(0, iteration - m_config.init_iterations);
        if (m_residual_adam)
            m_residual_adam->restore(AdamState{split(adam.m, field_count, residual_count),
                                               split(adam.v, field_count, residual_count), residual_steps});
        m_maps_ready = false;
        if (iteration >= m_config.init_iterations) {
            m_maps->evaluate_field(*m_field, m_config.refine_grid);
            m_maps->update();
            m_maps_ready = true;
        }
    }
}

void Trainer::prepare_maps() {
    if (m_maps_ready) return;
    m_maps->evaluate_field(*m_field, m_config.refine_grid);
    m_maps->set_residual_to(m_albedo_target, m_tactile_target);
    m_maps->update();
    m_maps_ready = true;
}

RangeExcess Trainer::albedo_range_excess(const Image& albedo) const {
    TDF_CHECK(texture_space());
    const ColourRange input = local_colour_range(m_albedo_target, m_texel_charts, kRangeMeasureRadius);
    return measure_range_excess(albedo, input, m_texel_charts, kRangeMeasureRadius, kRangeMeasureLimit);
}

BakedMaps Trainer::export_maps() const {
    if (!texture_space()) return bake_field(*m_field, *m_target.mesh, m_config.texture_size, m_config.gutter);
    TDF_CHECK(m_maps_ready);
    BakedMaps maps;
    maps.albedo = m_maps->export_albedo();
    maps.tactile_normal = m_maps->export_normal();
    maps.raster = m_atlas->raster;
    return maps;
}

std::vector<int> Trainer::predicted_texel_parts() const {
    if (!m_label_head) return {};
    const TexelAtlas& atlas = *m_atlas;
    const std::vector<int> predicted = m_label_head->predict(*m_field, atlas.points.data(), atlas.points.size());
    std::vector<int> labels(atlas.texel_count(), -1);
    for (std::size_t k = 0; k < predicted.size(); ++k) labels[atlas.texels[k]] = predicted[k];
    return labels;
}

// What iteration i computes: the phase table of spec 5.1 (i is the 0-based loop index).
struct Trainer::Phase {
    int i = 0;
    bool per_pixel_albedo = false;
    float albedo_weight = 0, tactile_weight = 0;
    bool visual_guidance = false, tactile_guidance = false;
};

Trainer::Phase Trainer::phase_of(int i) const {
    const RunConfig& cfg = m_config;
    Phase phase;
    phase.i = i;
    phase.per_pixel_albedo = i <= cfg.init_iterations;
    phase.albedo_weight = phase.per_pixel_albedo ? cfg.weights.albedo_init : cfg.weights.albedo_refine;
    phase.tactile_weight = i < cfg.init_iterations ? cfg.weights.tactile_init : cfg.weights.tactile_refine;
    phase.visual_guidance = m_visual_guidance && i >= cfg.init_iterations && cfg.weights.visual_guidance > 0;
    const bool tactile_backend = m_part_gate ? m_part_gate->has_guidance(cfg.weights.tactile_guidance)
                                             : m_tactile_guidance && cfg.weights.tactile_guidance > 0;
    phase.tactile_guidance = tactile_backend && i > cfg.init_iterations;
    return phase;
}

void Trainer::release_training_buffers() { m_batch = std::make_unique<Batch>(); }

LossRecord Trainer::step() {
    const int i = m_iteration;
    if (texture_space() && i < m_config.init_iterations) return fit_maps(i);
    const auto iteration_start = Clock::now();
    LossRecord record = loss_and_gradient(i);
    const auto t0 = Clock::now();
    update(i);
    m_times.adam += seconds_since(t0);
    ++m_iteration;
    record.seconds = seconds_since(iteration_start);
    return record;
}

LossRecord Trainer::loss_and_gradient(int i) {
    if (texture_space()) prepare_maps();
    if (m_label_head) m_label_gradient.assign(m_label_head->parameters().size(), 0.0f);  // trained in matching only
    if (m_part_gate && m_gate_labels_stale) {
        // The masks of the patch views: the head's parts at the texels, and in the gutter the part
        // of the texel each gutter texel copies (what a lookup there reads, where its gradient goes).
        const std::vector<int> predicted = predicted_texel_parts();
        std::vector<int> labels(predicted.size(), -1);
        for (std::size_t t = 0; t < labels.size(); ++t)
            if (m_atlas->source[t] >= 0) labels[t] = predicted[m_atlas->texels[std::size_t(m_atlas->source[t])]];
        m_part_gate->set_texel_part(std::move(labels));
        m_gate_labels_stale = false;
    }
    const Phase phase = phase_of(i);
    Rng rng = Rng::stream(m_seed, std::uint64_t(i));
    auto t0 = Clock::now();
    sample_cameras(rng);
    m_times.tracing += seconds_since(t0);

    LossRecord record;
    record.iteration = i;
    const std::size_t patches = std::size_t(m_config.patch_batch_size), all = m_batch->cameras.size();
    if (texture_space()) {
        // Patches send gradients only to the normal map and views only to the albedo map, so the
        // two halves run one after the other in the same buffers: an iteration's memory is that
        // of its larger half, not of both.
        begin_map_gradients();
        run_views(phase, 0, patches, record);
        swap_patch_and_view_buffers();
        run_views(phase, patches, all, record);
        swap_patch_and_view_buffers();
    } else {
        run_views(phase, 0, all, record);
    }

    double total = 0;
    for (const auto& [name, value] : record.terms) {
        if (!std::isfinite(value))
            throw_error("iteration {}: loss term '{}' is not finite ({}); the field was not updated", i, name, value);
        total += value;
    }
    record.terms["total"] = total;
    t0 = Clock::now();
    backward(i);
    m_times.field_backward += seconds_since(t0);
    return record;
}

void Trainer::run_views(const Phase& phase, std::size_t first, std::size_t last, LossRecord& record) {
    const std::size_t patches = std::size_t(m_config.patch_batch_size);
    auto t0 = Clock::now();
    trace_views(first, last);
    m_times.tracing += seconds_since(t0);

    t0 = Clock::now();
    evaluate_surface(phase.visual_guidance);
    m_times.field_forward += seconds_since(t0);

    t0 = Clock::now();
    const double guidance_before = m_times.guidance;
    if (first < patches) tactile_terms(phase, record);
    if (last > patches) visual_terms(phase, record);
    m_times.losses += seconds_since(t0) - (m_times.guidance - guidance_before);
    if (texture_space()) {
        t0 = Clock::now();
        scatter_map_gradients();
        m_times.field_backward += seconds_since(t0);
    }
}

void Trainer::swap_patch_and_view_buffers() {
    Batch& b = *m_batch;
    const std::size_t patches = std::size_t(m_config.patch_batch_size);
    const std::size_t views = b.gbuffers.size() - patches;
    for (std::size_t k = 0; k < std::min(patches, views); ++k) {
        std::swap(b.gbuffers[k], b.gbuffers[patches + k]);
        std::swap(b.point_of[k], b.point_of[patches + k]);
    }
}

std::vector<float> Trainer::gradient() const {
    std::vector<float> all = m_gradient;
    if (m_maps) all.insert(all.end(), m_residual_gradient.begin(), m_residual_gradient.end());
    if (m_label_head) {
        all.insert(all.end(), m_label_gradient.begin(), m_label_gradient.end());
        all.resize(all.size() + m_label_head->parameters().size() - m_label_gradient.size(), 0.0f);
    }
    return all;
}

void Trainer::set_parameters(const std::vector<float>& parameters) {
    const std::size_t field_count = m_field->parameter_count();
    const std::size_t residual_count = m_maps ? m_maps->residual().size() : 0;
    const std::size_t label_count = m_label_head ? m_label_head->parameters().size() : 0;
    if (parameters.size() != field_count + residual_count + label_count)
        throw_error("{} parameters given, this configuration has {}", parameters.size(),
                    field_count + residual_count + label_count);
    std::copy_n(parameters.begin(), field_count, m_field->parameters().begin());
    if (m_label_head) {
        std::copy_n(parameters.begin() + std::ptrdiff_t(field_count + residual_count), label_count,
                    m_label_head->parameters().begin());
        m_gate_labels_stale = true;
    }
    if (m_maps) {
        std::copy_n(parameters.begin() + std::ptrdiff_t(field_count), residual_count, m_maps->residual().begin());
        if (m_maps_ready) {
            m_maps->evaluate_field(*m_field, m_config.refine_grid);
            m_maps->update();
        }
    }
}

// ---- Matching phase of the texture-space optimizer ------------------------------------------
// The targets are known per texel, so the grid is fitted to them directly on a random sample of
// texels each iteration (dense supervision, no rendering), and the residual takes what the grid
// cannot hold when the phase ends (prepare_maps).
LossRecord Trainer::fit_maps(int i) {
    const auto start = Clock::now();
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const TexelAtlas& atlas = *m_atlas;
    Rng rng = Rng::stream(m_seed, std::uint64_t(i));
    const std::size_t n = std::min<std::size_t>(std::size_t(cfg.fit_texels), atlas.covered_count());
    std::vector<std::uint32_t>& picked = b.fit_texels;
    picked.resize(n);
    if (n == atlas.covered_count()) {
        for (std::size_t k = 0; k < n; ++k) picked[k] = std::uint32_t(k);
    } else {
        for (std::size_t k = 0; k < n; ++k) picked[k] = std::uint32_t(rng.uniform_int(0, int(atlas.covered_count()) - 1));
    }
    b.points.resize(n);
    for (std::size_t k = 0; k < n; ++k) b.points[k] = atlas.points[picked[k]];
    b.outputs.resize(n);
    m_field->evaluate(b.points.data(), n, b.outputs.data(), b.field_cache);
    b.grads.assign(n, FieldOutputGrads{});

    const float wa = cfg.weights.texture_albedo, wt = cfg.weights.texture_tactile;
    std::vector<double> partial(chunk_count(n, kPixelGrain) * 2, 0.0);
    parallel_for(n, kPixelGrain, [&](std::size_t begin, std::size_t end) {
        double albedo_sum = 0, tactile_sum = 0;
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = atlas.texels[picked[k]];
            const float* ta = m_albedo_target.data() + 3 * t;
            const Vec3f target_normal{m_tactile_target.data()[3 * t], m_tactile_target.data()[3 * t + 1],
                                      m_tactile_target.data()[3 * t + 2]};
            const Vec3f e = b.outputs[k].albedo - Vec3f{ta[0], ta[1], ta[2]};
            albedo_sum += double(dot(e, e));
            // mean over texels x 3 channels of the squared error; mean over texels of 1 - cos.
            b.grads[k].d_albedo = e * (2.0f * wa / (3.0f * float(n)));
            const Vec3f p = b.outputs[k].normal;  // unit
            tactile_sum += 1.0 - double(dot(p, target_normal));
            b.grads[k].d_normal = normalize_backward(p, target_normal * (-wt / float(n)), 1e-12f);
        }
        const std::size_t c = begin / kPixelGrain;
        partial[2 * c] = albedo_sum;
        partial[2 * c + 1] = tactile_sum;
    });
    double albedo_sum = 0, tactile_sum = 0;
    for (std::size_t c = 0; c < partial.size() / 2; ++c) albedo_sum += partial[2 * c], tactile_sum += partial[2 * c + 1];
    LossRecord record;
    record.iteration = i;
    record.terms["texture_albedo"] = wa * albedo_sum / (3.0 * double(n));
    record.terms["texture_tactile"] = wt * tactile_sum / double(n);
    record.terms["total"] = record.terms["texture_albedo"] + record.terms["texture_tactile"];
    std::fill(m_gradient.begin(), m_gradient.end(), 0.0f);
    if (m_label_head) {
        record.terms["texture_label"] = fit_labels(n);
        record.terms["total"] += record.terms["texture_label"];
    }
    for (const auto& [name, value] : record.terms)
        if (!std::isfinite(value))
            throw_error("iteration {}: loss term '{}' is not finite ({}); the field was not updated", i, name, value);
    m_field->backward(b.points.data(), b.grads.data(), n, m_gradient, b.field_cache);
    for (float g : m_gradient)
        if (!std::isfinite(g)) throw_error("iteration {}: the field gradient is not finite; the field was not updated", i);
    for (float g : m_label_gradient)
        if (!std::isfinite(g)) throw_error("iteration {}: the label head gradient is not finite; nothing was updated", i);
    m_adam->step(m_field->parameters(), m_gradient);
    if (m_label_head) {
        m_label_adam->step(m_label_head->parameters(), m_label_gradient);
        m_gate_labels_stale = true;
    }
    ++m_iteration;
    if (m_iteration == cfg.init_iterations) prepare_maps();
    record.seconds = seconds_since(start);
    m_times.matching += record.seconds;
    return record;
}

// Multi-part: cross-entropy of the label head against the known part of each fit texel, weight
// 1 (the reference's lambda_label_field), mean over the texels that have a part.
double Trainer::fit_labels(std::size_t n) {
    const Batch& b = *m_batch;
    std::vector<int> labels(n);
    for (std::size_t k = 0; k < n; ++k) labels[k] = (*m_target.texel_parts)[m_atlas->texels[b.fit_texels[k]]];
    m_label_gradient.assign(m_label_head->parameters().size(), 0.0f);
    return m_label_head->loss_and_gradient(*m_field, b.points.data(), labels.data(), n, kLabelWeight, m_label_gradient,
                                           &m_gradient);
}

// ---- 1. Cameras: patches first, then visual views (the order of random draws of spec 9) ----
void Trainer::sample_cameras(Rng& rng) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const int P = cfg.patch_batch_size, B = cfg.batch_size, R = cfg.patch_resolution, S = cfg.resolution;
    b.cameras.resize(std::size_t(P + B));
    b.gbuffers.resize(std::size_t(P + B));
    b.views.resize(std::size_t(B));
    b.lights.resize(std::size_t(B));
    for (int k = 0; k < P; ++k)
        b.cameras[std::size_t(k)] = sample_patch_view(rng, *m_target.mesh, R, cfg.patch_distance, cfg.patch_half_extent);
    VisualViewOptions view_options;
    view_options.resolution = S;
    view_options.random_ssaa = cfg.max_ssaa > 1.0f;
    for (int k = 0; k < B; ++k) {
        VisualView& v = b.views[std::size_t(k)];
        v = sample_visual_view(rng, view_options);
        if (v.ssaa > cfg.max_ssaa) {  // the reference's range is [1, 2]; a smaller cap re-sizes
            v.ssaa = cfg.max_ssaa;
            v.internal_width = v.internal_height = ssaa_internal_resolution(S, v.ssaa);
            v.camera.width = v.camera.height = v.internal_width;
        }
        b.cameras[std::size_t(P + k)] = v.camera;
        b.lights[std::size_t(k)] = sample_magic3d_light(rng, v.camera.position);
        if (cfg.fixed_training_light)  // drawn anyway: the same views as with the random light
            b.lights[std::size_t(k)] = magic3d_light(v.camera.position, radians(cfg.light_elevation_degrees),
                                                     radians(cfg.light_azimuth_degrees), cfg.light_distance);
    }
}

// ---- 2. Tracing, and the list of hits (background pixels need no evaluation, spec 13.18) ----
// Traces the cameras [first, last); the hits of this range replace the previous ones.
void Trainer::trace_views(std::size_t first, std::size_t last) {
    Batch& b = *m_batch;
    const std::size_t patches = std::size_t(m_config.patch_batch_size);
    for (std::size_t k = first; k < last; ++k)
        trace_gbuffer(*m_target.scene, *m_target.mesh, b.cameras[k], b.gbuffers[k]);
    b.point_of.resize(b.gbuffers.size());
    b.points.clear();
    b.patch_hit_count = 0;
    b.hit_pixel.clear();
    b.hit_view.clear();
    for (std::size_t k = first; k < last; ++k) {
        if (k == patches) b.patch_hit_count = b.hit_pixel.size();
        const GBuffer& g = b.gbuffers[k];
        std::vector<int>& point_of = b.point_of[k];
        point_of.resize(g.pixel_count());
        for (std::size_t p = 0; p < g.pixel_count(); ++p) {
            if (g.mask[p] > 0.0f) {
                point_of[p] = int(b.hit_pixel.size());
                if (!texture_space()) b.points.push_back(g.position[p]);  // the field's inputs
                b.hit_pixel.push_back(std::uint32_t(p));
                b.hit_view.push_back(std::uint16_t(k));
            } else {
                point_of[p] = -1;
            }
        }
    }
    if (last <= patches) b.patch_hit_count = b.hit_pixel.size();
}

// ---- 3. The surface at every hit: field (pixel) or learned maps (texture) -------------------
void Trainer::evaluate_surface(bool with_view_normals) {
    Batch& b = *m_batch;
    const std::size_t n = b.hit_pixel.size();
    b.outputs.resize(n);
    b.grads.assign(n, FieldOutputGrads{});
    if (!texture_space()) {
        m_field->evaluate(b.points.data(), n, b.outputs.data(), b.field_cache);
        return;
    }
    const MipTexture& albedo = m_maps->albedo();
    const MipTexture& normal = m_maps->normal();
    b.lookup_uv.resize(n);
    b.lookup_lod.resize(n);
    b.raw_normal.resize(n);
    b.curvature.assign(n, 0.0f);
    parallel_for(n, kPixelGrain, [&](std::size_t begin, std::size_t end) {
        TrilinearTaps taps;
        for (std::size_t q = begin; q < end; ++q) {
            const GBuffer& g = b.gbuffers[b.hit_view[q]];
            const std::size_t p = b.hit_pixel[q];
            // Both maps have the atlas's size, so one LOD serves both (spec 3.7).
            const float lod = albedo.level_of_detail(g.duv_dx[p], g.duv_dy[p]);
            b.lookup_uv[q] = g.uv[p];
            b.lookup_lod[q] = lod;
            albedo.taps(g.uv[p], lod, -1, taps);
            // Patches read only the normal map; views the albedo, and the normals only for the
            // visual guidance's shading and control images.
            const bool patch = q < b.patch_hit_count;
            if (!patch) b.outputs[q].albedo = gather3(albedo, taps);
            if (patch || with_view_normals) {
                b.raw_normal[q] = gather3(normal, taps);  // same size, same taps
                // Renormalised per pixel as the training renderer does with its maps (spec 3.1 step 5).
                b.outputs[q].normal = safe_normalize(b.raw_normal[q]);
            }
        }
    });
}

// ---- 4a. Tactile terms on patch view-space shading normals (spec 5.3, 5.5) -----------------
void Trainer::tactile_terms(const Phase& phase, LossRecord& record) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const int P = cfg.patch_batch_size, R = cfg.patch_resolution;
    const std::size_t patch_pixels = std::size_t(R) * std::size_t(R);
    b.patch_pred.resize(std::size_t(P) * patch_pixels);
    b.patch_target.resize(b.patch_pred.size());
    b.patch_grad.assign(b.patch_pred.size(), Vec3f{});
    for (int k = 0; k < P; ++k) {
        const GBuffer& g = b.gbuffers[std::size_t(k)];
        const ViewRotation rot = view_rotation(b.cameras[std::size_t(k)]);
        const std::vector<int>& point_of = b.point_of[std::size_t(k)];
        Vec3f* pred = b.patch_pred.data() + std::size_t(k) * patch_pixels;
        Vec3f* target = b.patch_target.data() + std::size_t(k) * patch_pixels;
        parallel_for(patch_pixels, kPixelGrain, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p) {
                const int q = point_of[p];
                if (q < 0) {
                    pred[p] = target[p] = Vec3f{};
                    continue;
                }
                pred[p] = tangent_to_view(g, p, rot, b.outputs[std::size_t(q)].normal);
                // The target laid over the atlas (texture evaluation: sampled exactly as the learned
                // map is, so the two agree when the maps equal their targets), or the material's map.
                target[p] = texture_space() ? tangent_to_view(g, p, rot, lookup_target_normal(std::size_t(q)))
                                            : target_view_normal(m_target, g, p, rot);
            }
        });
    }
    if (m_part_gate) {
        gated_tactile_terms(phase, record);
    } else if (phase.tactile_weight > 0 && P > 0) {
        record.terms["tactile_matching"] =
            phase.tactile_weight * tactile_matching_loss(b.patch_pred.data(), b.patch_target.data(),
                                                         b.patch_pred.size(), b.patch_grad.data(), phase.tactile_weight);
    }
    if (phase.tactile_guidance && P > 0 && !m_part_gate) {
        const auto g0 = Clock::now();
        GuidanceRequest request;
        request.kind = GuidanceKind::Tactile;
        request.prompt = "sks normal map";  // spec 5.5
        request.strength = kTactileGuidanceStrength;
        request.iteration = phase.i;
        request.seed = m_seed ^ (std::uint64_t(phase.i) << 20);
        request.pixels_per_texel = m_patch_pixels_per_texel;
        for (int k = 0; k < P; ++k)
            add_patch_to_request(request, b.gbuffers[std::size_t(k)], b.cameras[std::size_t(k)],
                                 b.patch_pred.data() + std::size_t(k) * patch_pixels, nullptr);
        const GuidanceResult result = m_tactile_guidance->refine(request);
        validate_result(request, result, m_tactile_guidance->name());
        if (!m_frames_folder.empty()) save_guidance_frames(m_frames_folder, phase.i, request, result);
        std::vector<Vec3f> refined(b.patch_pred.size());
        for (int k = 0; k < P; ++k)
            std::copy_n(result.refined[std::size_t(k)].data(), 3 * patch_pixels, &refined[std::size_t(k) * patch_pixels].x);
        const TactileGuidanceMetric metric = cfg.tactile_guidance_loss == TactileGuidanceLoss::Cosine
                                                 ? TactileGuidanceMetric::Cosine
                                                 : TactileGuidanceMetric::Mse;
        const float w = cfg.weights.tactile_guidance;
        record.terms["tactile_guidance"] =
            w * tactile_guidance_loss(metric, b.patch_pred.data(), refined.data(), refined.size(), b.patch_grad.data(), w);
        m_times.guidance += seconds_since(g0);
    }
    if (texture_space() && !m_part_gate) {
        // 1 - cos has unit curvature across the unit sphere; MSE on 3 components 2 / 3 per value.
        const double pixels = double(P) * double(patch_pixels);
        double kappa = phase.tactile_weight > 0 ? double(phase.tactile_weight) / pixels : 0.0;
        if (phase.tactile_guidance)
            kappa += double(cfg.weights.tactile_guidance) / pixels *
                     (cfg.tactile_guidance_loss == TactileGuidanceLoss::Cosine ? 1.0 : 2.0 / 3.0);
        for (int k = 0; k < P; ++k)
            for (int q : b.point_of[std::size_t(k)])
                if (q >= 0) b.curvature[std::size_t(q)] = float(kappa);
    }
    // Back through the view rotation and the TBN composition to the surface's tangent normal.
    for (int k = 0; k < P; ++k) {
        const GBuffer& g = b.gbuffers[std::size_t(k)];
        const ViewRotation rot = view_rotation(b.cameras[std::size_t(k)]);
        const std::vector<int>& point_of = b.point_of[std::size_t(k)];
        const Vec3f* grad = b.patch_grad.data() + std::size_t(k) * patch_pixels;
        parallel_for(patch_pixels, kPixelGrain, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p) {
                const int q = point_of[p];
                if (q < 0) continue;
                const TangentFrame f = frame_at(g, p);
                const Vec3f tangent_normal = b.outputs[std::size_t(q)].normal;
                const Vec3f d_world = view_space_normal_backward(rot, compose_shading_normal(f, tangent_normal), grad[p]);
                b.grads[std::size_t(q)].d_normal += compose_shading_normal_backward(f, tangent_normal, d_world);
            }
        });
    }
}

Vec3f Trainer::lookup_target_normal(std::size_t q) const {
    const Batch& b = *m_batch;
    TrilinearTaps taps;
    m_tactile_target_texture.taps(b.lookup_uv[q], b.lookup_lod[q], -1, taps);
    return safe_normalize(gather3(m_tactile_target_texture, taps));
}

// Multi-part (README "Multi-part textures"): each patch pixel's part from the gate's labels at
// its lookup, the per-part matching and guidance terms, and the Jacobi curvature per part.
void Trainer::gated_tactile_terms(const Phase& phase, LossRecord& record) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    PartGate& gate = *m_part_gate;
    const int P = cfg.patch_batch_size, R = cfg.patch_resolution;
    const std::size_t patch_pixels = std::size_t(R) * std::size_t(R);
    std::vector<std::int16_t> pixel_part(b.patch_pred.size(), -1), guidance_part(b.patch_pred.size(), -1);
    for (int k = 0; k < P; ++k) {
        const std::vector<int>& point_of = b.point_of[std::size_t(k)];
        parallel_for(patch_pixels, kPixelGrain, [&](std::size_t begin, std::size_t end) {
            TrilinearTaps taps;
            for (std::size_t p = begin; p < end; ++p) {
                const int q = point_of[p];
                if (q < 0) continue;
                const std::size_t i = std::size_t(k) * patch_pixels + p;
                pixel_part[i] = std::int16_t(gate.part_at(b.lookup_uv[std::size_t(q)]));
                m_maps->normal().taps(b.lookup_uv[std::size_t(q)], b.lookup_lod[std::size_t(q)], -1, taps);
                guidance_part[i] = std::int16_t(gate.pure_part(taps));
            }
        });
    }
    GatedPatches patches;
    patches.patches = P;
    patches.resolution = R;
    patches.pred = b.patch_pred.data();
    patches.target = b.patch_target.data();
    patches.part = pixel_part.data();
    patches.guidance_part = guidance_part.data();
    patches.grad = b.patch_grad.data();
    patches.add_patch = [&](GuidanceRequest& request, int k, const float* mask) {
        add_patch_to_request(request, b.gbuffers[std::size_t(k)], b.cameras[std::size_t(k)],
                             b.patch_pred.data() + std::size_t(k) * patch_pixels, mask);
    };
    GatedPhase gated;
    gated.iteration = phase.i;
    gated.matching_weight = phase.tactile_weight;
    gated.guidance = phase.tactile_guidance;
    gated.guidance_weight = cfg.weights.tactile_guidance;
    gated.metric = cfg.tactile_guidance_loss == TactileGuidanceLoss::Cosine ? TactileGuidanceMetric::Cosine
                                                                            : TactileGuidanceMetric::Mse;
    gated.seed = m_seed ^ (std::uint64_t(phase.i) << 20);
    gated.pixels_per_texel = m_patch_pixels_per_texel;
    const auto g0 = Clock::now();
    const auto frames = [&](const GuidanceRequest& request, const GuidanceResult& result, int part) {
        if (!m_frames_folder.empty())
            save_guidance_frames(m_frames_folder + "/part_" + gate.part(part).name, phase.i, request, result);
    };
    gate.tactile_terms(patches, gated, record, frames);
    if (gated.guidance) m_times.guidance += seconds_since(g0);
    // Jacobi denominators as the ungated terms', with each pixel's part's weights.
    const double pixels = double(P) * double(patch_pixels);
    const double guidance_curvature = cfg.tactile_guidance_loss == TactileGuidanceLoss::Cosine ? 1.0 : 2.0 / 3.0;
    const auto kappa = [&](int matching, int guiding) {
        double c = 0;
        if (matching >= 0 && phase.tactile_weight > 0) c += double(gate.matching_weight(matching, phase.tactile_weight)) / pixels;
        if (guiding >= 0 && gated.guidance && gate.part(guiding).backend)
            c += double(gate.guidance_weight(guiding, cfg.weights.tactile_guidance)) / pixels * guidance_curvature;
        return float(c);
    };
    for (int k = 0; k < P; ++k) {
        const std::vector<int>& point_of = b.point_of[std::size_t(k)];
        for (std::size_t p = 0; p < patch_pixels; ++p) {
            const std::size_t i = std::size_t(k) * patch_pixels + p;
            if (point_of[p] >= 0) b.curvature[std::size_t(point_of[p])] = kappa(pixel_part[i], guidance_part[i]);
        }
    }
}

// ---- 4b. Visual terms on the global views (spec 5.2, 5.4) -----------------------------------
void Trainer::visual_terms(const Phase& phase, LossRecord& record) {
    const RunConfig& cfg = m_config;
    const TriangleMesh& mesh = *m_target.mesh;
    Batch& b = *m_batch;
    const int P = cfg.patch_batch_size, B = cfg.batch_size, S = cfg.resolution;
    const bool visual_guidance = phase.visual_guidance;
    const std::size_t view_values = std::size_t(S) * std::size_t(S) * 3;
    b.albedo_pred.resize(std::size_t(B) * view_values);
    b.albedo_target.resize(b.albedo_pred.size());
    b.albedo_grad.assign(b.albedo_pred.size(), 0.0f);
    if (visual_guidance) {
        b.lambertian.resize(b.albedo_pred.size());
        b.lambertian_target.resize(b.albedo_pred.size());
        b.lambertian_grad.assign(b.albedo_pred.size(), 0.0f);
        b.shade.assign(b.hit_pixel.size(), 0.0f);
    }
    std::vector<Image> controls, masks, surfaces;
    for (int k = 0; k < B; ++k) {
        const std::size_t gi = std::size_t(P + k);
        const GBuffer& g = b.gbuffers[gi];
        const std::vector<int>& point_of = b.point_of[gi];
        const VisualView& view = b.views[std::size_t(k)];
        const bool resized = g.width != S || g.height != S;
        // Renders composited on white at the internal size, then resized to S x S (spec 3.8).
        const auto render_internal = [&](auto&& colour_of_hit, float* out) {
            if (b.internal.width() != g.width || b.internal.height() != g.height) b.internal = Image(g.width, g.height, 3);
            std::fill(b.internal.values().begin(), b.internal.values().end(), 1.0f);  // white background
            parallel_for(g.pixel_count(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
                for (std::size_t p = begin; p < end; ++p) {
                    const int q = point_of[p];
                    if (q < 0) continue;
                    const Vec3f c = colour_of_hit(p, std::size_t(q));
                    std::copy(&c.x, &c.x + 3, b.internal.data() + 3 * p);
                }
            });
            copy_into(resized ? resize_bilinear(b.internal, S, S) : b.internal, out);
        };
        float* pred = b.albedo_pred.data() + std::size_t(k) * view_values;
        render_internal([&](std::size_t, std::size_t q) { return b.outputs[q].albedo; }, pred);
        // The input's albedo: in texture space its bake over the atlas, sampled exactly as the learned
        // map is (same taps), so the learned map at its start renders identical images and only
        // what guidance asks for changes it; per pixel, the material itself (spec 3.1 step 5).
        const auto input_albedo = [&](std::size_t p, std::size_t q) {
            if (!texture_space()) return sample_albedo(*m_target.material, mesh, g, p, true);
            TrilinearTaps taps;
            m_albedo_target_texture.taps(b.lookup_uv[q], b.lookup_lod[q], -1, taps);
            return gather3(m_albedo_target_texture, taps);
        };
        render_internal(input_albedo, b.albedo_target.data() + std::size_t(k) * view_values);
        if (visual_guidance) {
            const Vec3f light = b.lights[std::size_t(k)];
            const ViewRotation rot = view_rotation(view.camera);
            render_internal(
                [&](std::size_t p, std::size_t q) {
                    // The shading normal is detached (spec 3.4): only the albedo gets gradient.
                    const Vec3f n_s = compose_shading_normal(frame_at(g, p), b.outputs[q].normal);
                    b.shade[q] = training_shade(n_s, light, g.position[p]);
                    return lambertian(b.outputs[q].albedo, b.shade[q]);
                },
                b.lambertian.data() + std::size_t(k) * view_values);
            // The input asset under the same light and relief: what relief-aware refinement keeps.
            render_internal(
                [&](std::size_t p, std::size_t q) { return lambertian(input_albedo(p, q), b.shade[q]); },
                b.lambertian_target.data() + std::size_t(k) * view_values);
            Image normals_internal(g.width, g.height, 3, 0.0f), mask_internal(g.width, g.height, 1, 0.0f);
            Image surface_internal(g.width, g.height, 3, 0.0f);
            for (std::size_t p = 0; p < g.pixel_count(); ++p) {
                const int q = point_of[p];
                if (q < 0) continue;
                const Vec3f n_v = tangent_to_view(g, p, rot, b.outputs[std::size_t(q)].normal);
                std::copy(&n_v.x, &n_v.x + 3, normals_internal.data() + 3 * p);
                const Vec3f s_v = view_space_normal(rot, g.normal[p]);
                std::copy(&s_v.x, &s_v.x + 3, surface_internal.data() + 3 * p);
                mask_internal.data()[p] = 1.0f;
            }
            controls.push_back(to_bae_control(resized ? resize_bilinear(normals_internal, S, S) : normals_internal));
            masks.push_back(resized ? resize_bilinear(mask_internal, S, S) : mask_internal);
            surfaces.push_back(resized ? resize_bilinear(surface_internal, S, S) : surface_internal);
        }
    }
    const ImageBatchShape shape{B, S, S, 3};
    if (phase.albedo_weight > 0 && B > 0) {
        const double value =
            phase.per_pixel_albedo
                ? mse_loss(b.albedo_pred.data(), b.albedo_target.data(), b.albedo_pred.size(), b.albedo_grad.data(),
                           phase.albedo_weight)
                : mean_colour_mse_loss(b.albedo_pred.data(), b.albedo_target.data(), shape, b.albedo_grad.data(),
                                       phase.albedo_weight);
        record.terms[phase.per_pixel_albedo ? "albedo_matching" : "albedo_mean_colour"] = phase.albedo_weight * value;
    }
    if (visual_guidance && B > 0) {
        const auto g0 = Clock::now();
        GuidanceRequest request;
        request.kind = GuidanceKind::Visual;
        request.prompt = m_target.prompt;
        request.negative_prompt = kNegativePrompt;
        request.strength = visual_guidance_strength(phase.i, cfg.init_iterations, cfg.iterations);
        request.iteration = phase.i;
        request.seed = m_seed ^ (std::uint64_t(phase.i) << 20) ^ 0x5649u;
        for (int k = 0; k < B; ++k) {
            Image image(S, S, 3), reference(S, S, 3);
            std::copy_n(b.lambertian.data() + std::size_t(k) * view_values, view_values, image.data());
            std::copy_n(b.lambertian_target.data() + std::size_t(k) * view_values, view_values, reference.data());
            request.images.push_back(std::move(image));
            request.reference_images.push_back(std::move(reference));
        }
        request.control = std::move(controls);
        request.masks = std::move(masks);
        request.surface_normals = std::move(surfaces);
        GuidanceResult result = m_visual_guidance->refine(request);
        validate_result(request, result, m_visual_guidance->name());
        if (!m_frames_folder.empty()) save_guidance_frames(m_frames_folder, phase.i, request, result);
        std::vector<float> refined(b.lambertian.size());
        for (int k = 0; k < B; ++k) {
            // Background forced to white (spec 5.4).
            Image& r = result.refined[std::size_t(k)];
            const Image& m = request.masks[std::size_t(k)];
            for (std::size_t p = 0; p < r.pixel_count(); ++p)
                if (m.data()[p] == 0.0f) std::fill_n(r.data() + 3 * p, 3, 1.0f);
            copy_into(r, refined.data() + std::size_t(k) * view_values);
        }
        const float w = cfg.weights.visual_guidance, ws = cfg.weights.visual_guidance_structural;
        if (cfg.visual_guidance_loss == "mse") {
            record.terms["visual_guidance_mse"] =
                w * mse_loss(b.lambertian.data(), refined.data(), refined.size(), b.lambertian_grad.data(), w);
        } else {
            const double l1 = l1_loss(b.lambertian.data(), refined.data(), refined.size(), b.lambertian_grad.data(), w);
            const double structural =
                ws > 0 ? ssim_loss(b.lambertian.data(), refined.data(), shape, b.lambertian_grad.data(), w * ws) : 0.0;
            record.terms["visual_guidance_l1"] = w * l1;
            record.terms["visual_guidance_structural"] = w * ws * structural;
        }
        m_times.guidance += seconds_since(g0);
    }
    // Back through the resize (its adjoint) to the internal pixels, then to the surface's albedo.
    for (int k = 0; k < B; ++k) {
        const std::size_t gi = std::size_t(P + k);
        const GBuffer& g = b.gbuffers[gi];
        const std::vector<int>& point_of = b.point_of[gi];
        const bool resized = g.width != S || g.height != S;
        const auto to_internal = [&](const std::vector<float>& grad) {
            Image out(S, S, 3);
            std::copy_n(grad.data() + std::size_t(k) * view_values, view_values, out.data());
            return resized ? resize_bilinear_adjoint(out, g.width, g.height) : out;
        };
        const Image albedo_grad = to_internal(b.albedo_grad);
        const Image lambertian_grad = visual_guidance ? to_internal(b.lambertian_grad) : Image();
        // Jacobi denominators: per value, 2 w / N for squared errors (an L1 term counts as a
        // squared error at a 0.1 scale), spread over the internal pixels as the resize spreads
        // the gradients.
        const double values = double(b.albedo_pred.size());
        const double ssaa_share = double(S) * double(S) / (double(g.width) * double(g.height));
        const double albedo_kappa =
            (phase.per_pixel_albedo ? 2.0 * double(phase.albedo_weight) / values : 0.0) * ssaa_share;
        const double lambertian_kappa =
            visual_guidance ? (cfg.visual_guidance_loss == "mse" ? 2.0 : 10.0) * double(cfg.weights.visual_guidance) /
                                  values * ssaa_share
                            : 0.0;
        parallel_for(g.pixel_count(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p) {
                const int q = point_of[p];
                if (q < 0) continue;
                if (texture_space()) {
                    const double shade = visual_guidance ? double(b.shade[std::size_t(q)]) : 0.0;
                    b.curvature[std::size_t(q)] = float(albedo_kappa + lambertian_kappa * shade * shade);
                }
                const float* ga = albedo_grad.data() + 3 * p;
                Vec3f d{ga[0], ga[1], ga[2]};
                if (visual_guidance) {
                    const float* gl = lambertian_grad.data() + 3 * p;
                    d += lambertian_backward(b.shade[std::size_t(q)], Vec3f{gl[0], gl[1], gl[2]});
                }
                b.grads[std::size_t(q)].d_albedo += d;
            }
        });
    }
}

// ---- 5. Backward to the parameters ----------------------------------------------------------
void Trainer::begin_map_gradients() {
    Batch& b = *m_batch;
    b.albedo_gradient.reset(m_maps->albedo(), 4);
    b.normal_gradient.reset(m_maps->normal(), 4);
}

// The adjoint of the map lookups: each hit's gradient goes to the texels it blended. Albedo and
// normal maps are independent, so the two scatters run side by side, each in hit order (fixed
// summation order: the same bits on any thread count).
// Channel 3 accumulates the hits' loss curvature through the same taps (the Jacobi step).
void Trainer::scatter_map_gradients() {
    Batch& b = *m_batch;
    const std::size_t n = b.hit_pixel.size();
    const MipTexture& albedo = m_maps->albedo();
    const std::size_t patch_hits = b.patch_hit_count;
    parallel_for(2, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t task = begin; task < end; ++task) {
            TrilinearTaps taps;
            MipGradient& target = task == 0 ? b.albedo_gradient : b.normal_gradient;
            // Patches are hits [0, patch_hits) and send normal gradients; views send albedo ones.
            const std::size_t first = task == 0 ? patch_hits : 0, last = task == 0 ? n : patch_hits;
            for (std::size_t q = first; q < last; ++q) {
                const FieldOutputGrads& g = b.grads[q];
                const Vec3f d = task == 0 ? g.d_albedo : normalize_backward(b.raw_normal[q], g.d_normal, 1e-10f);
                const float value[4] = {d.x, d.y, d.z, b.curvature[q]};
                if (value[0] == 0.0f && value[1] == 0.0f && value[2] == 0.0f && value[3] == 0.0f) continue;
                albedo.taps(b.lookup_uv[q], b.lookup_lod[q], -1, taps);
                target.add(taps, value);
            }
        }
    });
}

void Trainer::backward(int i) {
    Batch& b = *m_batch;
    const std::size_t n = b.hit_pixel.size();
    std::fill(m_gradient.begin(), m_gradient.end(), 0.0f);
    if (!texture_space()) {
        m_field->backward(b.points.data(), b.grads.data(), n, m_gradient, b.field_cache);
        for (float g : m_gradient)
            if (!std::isfinite(g)) throw_error("iteration {}: the field gradient is not finite; the field was not updated", i);
        return;
    }
    // The hits were scattered into the map gradients view by view (scatter_map_gradients).
    b.albedo_gradient.collapse();
    b.normal_gradient.collapse();
    m_residual_gradient.assign(m_maps->residual().size(), 0.0f);
    m_maps->backward(b.albedo_gradient.level0(), b.normal_gradient.level0(), m_residual_gradient,
                     m_config.refine_grid ? &b.texel_grads : nullptr);
    if (m_config.refine_grid) m_maps->field_backward(*m_field, b.texel_grads, m_gradient);
    for (float g : m_residual_gradient)
        if (!std::isfinite(g)) throw_error("iteration {}: the map gradient is not finite; the maps were not updated", i);
    for (float g : m_gradient)
        if (!std::isfinite(g)) throw_error("iteration {}: the field gradient is not finite; the field was not updated", i);
}

// ---- 6. The Adam step (and, texture evaluation, the maps it changed) ------------------------
void Trainer::update(int i) {
    if (!texture_space()) {
        m_adam->step(m_field->parameters(), m_gradient);
        return;
    }
    (void)i;
    if (m_config.residual_optimizer == "jacobi")
        m_maps->jacobi_step(m_batch->albedo_gradient.level0(), m_batch->normal_gradient.level0(), m_config.residual_step,
                            m_config.residual_step_smoothing);
    else
        m_residual_adam->step(m_maps->residual(), m_residual_gradient);
    if (m_config.refine_grid) {
        m_adam->step(m_field->parameters(), m_gradient);
        m_maps->evaluate_field(*m_field, m_config.refine_grid);
    }
    m_maps->update();
}

Camera Trainer::held_out_view(int k) const {
    VisualViewOptions view_options;
    view_options.resolution = m_config.resolution;
    view_options.random_ssaa = false;
    Rng rng = Rng::stream(m_seed ^ kHeldOutStream, std::uint64_t(k));
    return sample_visual_view(rng, view_options).camera;
}

Camera Trainer::held_out_patch(int k) const {
    Rng rng = Rng::stream(m_seed ^ kHeldOutStream ^ 0x7061746368ULL, std::uint64_t(k));
    return sample_patch_view(rng, *m_target.mesh, m_config.patch_resolution, m_config.patch_distance,
                             m_config.patch_half_extent);
}

void Trainer::evaluate_hits(const GBuffer& g, std::vector<FieldOutputs>& outputs) const {
    std::vector<std::size_t> hits;
    for (std::size_t p = 0; p < g.pixel_count(); ++p)
        if (g.mask[p] > 0.0f) hits.push_back(p);
    outputs.resize(hits.size());
    if (!texture_space()) {
        std::vector<Vec3f> points(hits.size());
        for (std::size_t q = 0; q < hits.size(); ++q) points[q] = g.position[hits[q]];
        m_field->evaluate(points.data(), points.size(), outputs.data());
        return;
    }
    if (!m_maps_ready) throw_error("the learned maps exist only after the matching phase");
    const MipTexture& albedo = m_maps->albedo();
    const MipTexture& normal = m_maps->normal();
    parallel_for(hits.size(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
        TrilinearTaps taps;
        for (std::size_t q = begin; q < end; ++q) {
            const std::size_t p = hits[q];
            albedo.taps(g.uv[p], albedo.level_of_detail(g.duv_dx[p], g.duv_dy[p]), -1, taps);
            outputs[q].albedo = gather3(albedo, taps);
            outputs[q].normal = safe_normalize(gather3(normal, taps));
            outputs[q].label[0] = outputs[q].label[1] = 0.0f;
        }
    });
}

void Trainer::trace_and_evaluate(const Camera& camera, GBuffer& g, std::vector<FieldOutputs>& outputs) const {
    trace_gbuffer(*m_target.scene, *m_target.mesh, camera, g);
    evaluate_hits(g, outputs);
}

namespace {
// The learned images of a traced view; `outputs` holds the field at its hits in pixel order.
LearnedImages learned_images(const Camera& camera, const GBuffer& g, const std::vector<FieldOutputs>& outputs) {
    LearnedImages images{Image(g.width, g.height, 3, 1.0f), Image(g.width, g.height, 3, 0.0f),
                         Image(g.width, g.height, 1, 0.0f)};
    const ViewRotation rot = view_rotation(camera);
    std::size_t q = 0;
    for (std::size_t p = 0; p < g.pixel_count(); ++p) {
        if (g.mask[p] <= 0.0f) continue;
        const FieldOutputs& out = outputs[q++];
        const Vec3f n_v = tangent_to_view(g, p, rot, out.normal);
        std::copy(&out.albedo.x, &out.albedo.x + 3, images.albedo.data() + 3 * p);
        std::copy(&n_v.x, &n_v.x + 3, images.view_normals.data() + 3 * p);
        images.mask.data()[p] = 1.0f;
    }
    return images;
}
}  // namespace

LearnedImages Trainer::render_learned(const Camera& camera) const {
    GBuffer g;
    std::vector<FieldOutputs> outputs;
    trace_and_evaluate(camera, g, outputs);
    return learned_images(camera, g, outputs);
}

QualityReport Trainer::evaluate_held_out() const {
    const RunConfig& cfg = m_config;
    const TriangleMesh& mesh = *m_target.mesh;
    QualityReport report;
    double squared = 0, max_error = 0, alignment = 0, added_alignment = 0;
    const MeshSeams mesh_seams(mesh);
    std::size_t values_fg = 0, values_full = 0;
    GBuffer g;
    std::vector<FieldOutputs> outputs, inputs, added;
    // The seam measures of one view's learned maps and of the input's own (its albedo through its
    // UVs; in texture space also the tactile map laid over the atlas, sampled as the learned map is).
    struct ViewSeams {
        SeamJump albedo, normal, input_albedo, input_normal;
    };
    // One view: albedo error against the input and seam jumps; `scored` views also count in the
    // PSNR and the correlation (the turntable's only in its own seam measure).
    const auto measure_view = [&](const Camera& camera, bool scored, ViewSeams& seams) {
        trace_and_evaluate(camera, g, outputs);
        if (scored) values_full += 3 * g.pixel_count();  // background: white in both, zero error (spec 5.2)
        inputs.resize(outputs.size());
        added.resize(outputs.size());
        std::size_t q = 0;
        for (std::size_t p = 0; p < g.pixel_count(); ++p) {
            if (g.mask[p] <= 0.0f) continue;
            FieldOutputs& input = inputs[q];
            input.albedo = sample_albedo(*m_target.material, mesh, g, p, true);
            input.normal = Vec3f{0, 0, 1};
            // What the run added (issue 29): against the input as the learned map samples it
            // (the atlas bake through the same taps), so resampling is not counted as added.
            added[q] = outputs[q];
            added[q].albedo = outputs[q].albedo - input.albedo;
            if (texture_space()) {
                TrilinearTaps taps;
                const float lod = m_tactile_target_texture.level_of_detail(g.duv_dx[p], g.duv_dy[p]);
                m_tactile_target_texture.taps(g.uv[p], lod, -1, taps);
                input.normal = safe_normalize(gather3(m_tactile_target_texture, taps));
                m_albedo_target_texture.taps(g.uv[p], lod, -1, taps);  // both targets: the atlas's size
                added[q].albedo = outputs[q].albedo - gather3(m_albedo_target_texture, taps);
            }
            const Vec3f e = outputs[q++].albedo - input.albedo;
            if (!scored) continue;
            for (int c = 0; c < 3; ++c) {
                squared += double(e[c]) * e[c];
                max_error = std::max(max_error, double(std::fabs(e[c])));
            }
            values_fg += 3;
        }
        const LearnedImages learned = learned_images(camera, g, outputs);
        const LearnedImages input = learned_images(camera, g, inputs);
        if (scored) {
            alignment += colour_geometry_correlation(learned.albedo, learned.view_normals, learned.mask);
            // What the run added, without the input's own detail (prints, label edges, which
            // must stay and would dominate the measure on a printed asset), against the relief's
            // own curvature as relief_shading takes it: the view normals minus the surface's, so
            // the mesh's curvature (large near a silhouette) is not taken for relief.
            Image relief = learned.view_normals;
            const ViewRotation rot = view_rotation(camera);
            for (std::size_t p = 0; p < g.pixel_count(); ++p) {
                if (g.mask[p] <= 0.0f) continue;
                const Vec3f surface = view_space_normal(rot, g.normal[p]);
                for (int c = 0; c < 3; ++c) relief.data()[3 * p + std::size_t(c)] -= surface[c];
            }
            added_alignment +=
                colour_geometry_correlation(learned_images(camera, g, added).albedo, relief, learned.mask);
        }
        seams.albedo.add(g, learned.albedo, mesh_seams);
        seams.input_albedo.add(g, input.albedo, mesh_seams);
        seams.normal.add(g, learned.view_normals, mesh_seams);
        seams.input_normal.add(g, input.view_normals, mesh_seams);
    };
    ViewSeams held_out;
    for (int k = 0; k < cfg.held_out_views; ++k) measure_view(held_out_view(k), true, held_out);
    ViewSeams turntable;
    const TurntableFraming framing = turntable_framing(mesh);
    for (int k = 0; k < cfg.turntable_views; ++k)
        measure_view(turntable_camera(framing, k, cfg.turntable_views, cfg.turntable_resolution), false, turntable);
    report.turntable_seam_jump_ratio_albedo = turntable.albedo.ratio();
    report.turntable_seam_jump_ratio_normal = turntable.normal.ratio();
    report.turntable_input_seam_jump_ratio_albedo = turntable.input_albedo.ratio();
    report.turntable_input_seam_jump_ratio_normal = turntable.input_normal.ratio();
    report.turntable_cone_jump_ratio_albedo = turntable.albedo.cone_ratio();
    report.turntable_input_cone_jump_ratio_albedo = turntable.input_albedo.cone_ratio();
    report.turntable_seam_pairs = turntable.albedo.seam_pairs;
    report.turntable_cone_pairs = turntable.albedo.cone_pairs;
    report.seam_jump_ratio_albedo = held_out.albedo.ratio();
    report.seam_jump_ratio_normal = held_out.normal.ratio();
    report.seam_pairs = held_out.albedo.seam_pairs;
    report.input_seam_jump_ratio_albedo = held_out.input_albedo.ratio();
    const auto psnr = [](double sum, std::size_t count) {
        if (count == 0) return 0.0;
        const double mse = sum / double(count);
        return mse > 0 ? 10.0 * std::log10(1.0 / mse) : 99.0;
    };
    report.albedo_psnr_foreground = psnr(squared, values_fg);
    report.albedo_psnr_full = psnr(squared, values_full);
    report.albedo_max_error = max_error;
    report.colour_geometry_correlation = cfg.held_out_views > 0 ? alignment / cfg.held_out_views : 0.0;
    report.added_colour_geometry_correlation = cfg.held_out_views > 0 ? added_alignment / cfg.held_out_views : 0.0;
    report.views = cfg.held_out_views;

    double cosine_sum = 0;
    std::size_t cosine_count = 0;
    std::vector<Vec3f> learned_tangent, target_tangent;
    for (int k = 0; k < cfg.held_out_patches; ++k) {
        const Camera camera = held_out_patch(k);
        trace_and_evaluate(camera, g, outputs);
        const LearnedImages learned = learned_images(camera, g, outputs);
        const ViewRotation rot = view_rotation(camera);
        std::size_t q = 0;
        for (std::size_t p = 0; p < g.pixel_count(); ++p) {
            if (g.mask[p] <= 0.0f) continue;
            const float* n = learned.view_normals.data() + 3 * p;
            Vec3f target;
            if (m_target.tactile_target_override) {
                // Multi-part: the composed target over the atlas, sampled as the learned map is.
                TrilinearTaps taps;
                m_tactile_target_texture.taps(
                    g.uv[p], m_tactile_target_texture.level_of_detail(g.duv_dx[p], g.duv_dy[p]), -1, taps);
                target = safe_normalize(gather3(m_tactile_target_texture, taps));
            } else {
                target = target_tangent_normal(m_target, g, p);
            }
            cosine_sum += cosine_similarity({n[0], n[1], n[2]}, tangent_to_view(g, p, rot, target));
            ++cosine_count;
            learned_tangent.push_back(outputs[q++].normal);
            target_tangent.push_back(target);
        }
    }
    report.tactile_mean_cosine = cosine_count ? cosine_sum / double(cosine_count) : 0.0;
    if (m_target.material->tactile) {
        const std::vector<double> exemplar = tilt_histogram(m_target.material->tactile->level(0));
        report.tactile_tilt_distance =
            histogram_l1_distance(tilt_histogram(learned_tangent.data(), learned_tangent.size()), exemplar);
        report.target_tilt_distance =
            histogram_l1_distance(tilt_histogram(target_tangent.data(), target_tangent.size()), exemplar);
    }
    report.patches = cfg.held_out_patches;
    return report;
}

Json QualityReport::to_json() const {
    return {{"albedo_psnr_foreground_db", albedo_psnr_foreground},
            {"albedo_psnr_full_image_db", albedo_psnr_full},
            {"albedo_max_error", albedo_max_error},
            {"tactile_mean_cosine", tactile_mean_cosine},
            {"colour_geometry_correlation", colour_geometry_correlation},
            {"added_colour_geometry_correlation", added_colour_geometry_correlation},
            {"tactile_tilt_distance", tactile_tilt_distance},
            {"target_tilt_distance", target_tilt_distance},
            {"seam_jump_ratio_albedo", seam_jump_ratio_albedo},
            {"seam_jump_ratio_normal", seam_jump_ratio_normal},
            {"input_seam_jump_ratio_albedo", input_seam_jump_ratio_albedo},
            {"seam_pixel_pairs", seam_pairs},
            {"turntable_seam_jump_ratio_albedo", turntable_seam_jump_ratio_albedo},
            {"turntable_seam_jump_ratio_normal", turntable_seam_jump_ratio_normal},
            {"turntable_input_seam_jump_ratio_albedo", turntable_input_seam_jump_ratio_albedo},
            {"turntable_seam_pixel_pairs", turntable_seam_pairs},
            {"turntable_input_seam_jump_ratio_normal", turntable_input_seam_jump_ratio_normal},
            {"turntable_cone_jump_ratio_albedo", turntable_cone_jump_ratio_albedo},
            {"turntable_input_cone_jump_ratio_albedo", turntable_input_cone_jump_ratio_albedo},
            {"turntable_cone_pixel_pairs", turntable_cone_pairs},
            {"held_out_views", views},
            {"held_out_patches", patches}};
}

Json StageTimes::to_json(int iterations) const {
    const double n = std::max(iterations, 1);
    return {{"tracing", tracing / n},     {"field_forward", field_forward / n}, {"losses", losses / n},
            {"guidance", guidance / n},   {"field_backward", field_backward / n}, {"adam", adam / n},
            {"matching_total", matching}, {"iterations", iterations}};
}

}  // namespace tdf
