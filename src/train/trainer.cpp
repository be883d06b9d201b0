// The trainer's construction and its iteration: the targets and optimizers it builds, checkpoints
// (parameters, restore), the phase table, and step() / loss_and_gradient(), which run the stages of
// the other trainer_*.cpp files in order (trainer_impl.h lists them).
// Reads: the TrainingTarget and RunConfig. Writes: everything the Trainer owns.
#include "trainer_impl.h"

#include <tdf/atlas/uv_metrics.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/release.h>
#include <tdf/train/part_gating.h>
#include <tdf/train/part_label_head.h>
#include <tdf/train/tactile_seam_blend.h>
#include <tdf/train/texture_fidelity.h>

#include <cmath>
#include <utility>

namespace tdf {

using namespace trainer_detail;

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
        TDF_CHECK(target.tactile_target_override && !target.part_names.empty());
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
        Image albedo_target = tdf::albedo_target(*m_atlas, *target.material, *target.mesh);
        Image tactile_target;
        if (parts) {
            const int size = config.texture_size;
            if (target.tactile_target_override->width() != size || target.tactile_target_override->height() != size ||
                target.tactile_target_override->channels() != 3 ||
                target.texel_parts->size() != std::size_t(size) * std::size_t(size))
                throw_error("multi-part: the composed tactile target and the part labels must be {0}x{0} "
                            "(optimize.texture_size)", size);
            tactile_target = *target.tactile_target_override;
        } else {
            tactile_target = tdf::tactile_target(*m_atlas, *target.material);
            m_seam_blend = cross_fade_tactile_seams(tactile_target, *m_atlas, *target.mesh, *target.material,
                                                    config.tactile_seam_band);
        }
        m_albedo_target_texture = MipTexture(std::move(albedo_target));
        m_tactile_target_texture = MipTexture(std::move(tactile_target));
        m_atlas->release_target_inputs();  // the targets are laid: 20 bytes a texel stay behind
        m_maps = std::make_unique<LearnedMaps>(*m_atlas);
        m_texel_charts = atlas_texel_charts(*m_atlas, *target.mesh);
        set_albedo_bounds();
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
    TDF_CHECK(!m_training_finished);  // the residual is gone
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
    m_maps->set_residual_to(albedo_target(), tactile_target());
    m_maps->update();
    m_maps_ready = true;
}

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

void Trainer::set_albedo_bounds() {
    const RunConfig& config = m_config;
    if (config.albedo_range_radius <= 0) return;
    // The refinement's colour bound (issue 29): the input's local range, widened.
    ColourRange bound = local_colour_range(albedo_target(), m_texel_charts, config.albedo_range_radius);
    for (float& v : bound.low.values()) v -= config.albedo_range_darken;
    for (float& v : bound.high.values()) v += config.albedo_range_lighten;
    m_maps->set_albedo_bounds(std::move(bound.low), std::move(bound.high));
}

void Trainer::release_derived_state() {
    if (!texture_space() || m_derived_released) return;
    release_training_buffers();
    m_maps->release_derived();
    m_maps->set_albedo_bounds(Image(), Image());  // recomputed from the input by restore_derived_state()
    m_albedo_target_texture.drop_levels();
    m_tactile_target_texture.drop_levels();
    m_derived_released = true;
}

void Trainer::restore_derived_state() {
    if (!m_derived_released) return;
    if (m_training_finished) {
        m_maps->restore_levels();  // the outputs and bounds left with finish_training()
    } else {
        m_maps->restore_derived(*m_field, m_config.refine_grid);
        set_albedo_bounds();
    }
    m_albedo_target_texture.restore_levels();
    m_tactile_target_texture.restore_levels();
    m_derived_released = false;
}

void Trainer::finish_training() {
    release_training_buffers();
    m_residual_adam.reset();
    release(m_residual_gradient);
    if (m_maps) m_maps->release_training_state();
    m_training_finished = true;
}

LossRecord Trainer::step() {
    TDF_CHECK(!m_training_finished && !m_derived_released);
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
    if (m_maps && m_residual_adam) {
        all.insert(all.end(), m_residual_gradient.begin(), m_residual_gradient.end());
    } else if (m_maps) {
        // The Jacobi step keeps no residual gradient: it is derived from the folded map gradients,
        // which hold it until update() smooths them.
        TDF_CHECK(m_map_gradients_unstepped);
        std::vector<float> residual;
        m_maps->add_residual_gradient(m_batch->albedo_gradient.level0(), m_batch->normal_gradient.level0(), residual);
        all.insert(all.end(), residual.begin(), residual.end());
    }
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

}  // namespace tdf
