// Held-out quality: views and patches from a stream no training iteration draws from, the
// learned images of a camera, and the QualityReport (PSNR, tactile cosine, seam and tilt
// measures) and StageTimes as JSON.
// Reads: the field or the learned maps, the material, the targets over the atlas.
// Writes nothing in the trainer (const).
#include "trainer_impl.h"

#include <tdf/core/error.h>
#include <tdf/guidance/relief_shading.h>
#include <tdf/loss/image_loss.h>
#include <tdf/render/material_sampling.h>
#include <tdf/scene/view_sampler.h>
#include <tdf/tactile/relief_statistics.h>
#include <tdf/train/asset_export.h>
#include <tdf/train/texture_fidelity.h>

#include <cmath>

namespace tdf {

using namespace trainer_detail;

namespace {

// Held-out views and patches come from streams far away from any iteration index.
constexpr std::uint64_t kHeldOutStream = 0x68656c646f7574ULL;

}  // namespace

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

namespace {
// The pixels of g's hits in pixel order: hit q is pixel hits[q] (outputs[q] is its field value).
void list_hits(const GBuffer& g, std::vector<std::size_t>& hits) {
    hits.clear();
    for (std::size_t p = 0; p < g.pixel_count(); ++p)
        if (g.mask[p] > 0.0f) hits.push_back(p);
}
}  // namespace

void Trainer::evaluate_hits(const GBuffer& g, std::vector<FieldOutputs>& outputs) const {
    std::vector<std::size_t> hits;
    list_hits(g, hits);
    outputs.resize(hits.size());
    if (!texture_space()) {
        std::vector<Vec3f> points(hits.size());
        for (std::size_t q = 0; q < hits.size(); ++q) points[q] = g.position[hits[q]];
        m_field->evaluate(points.data(), points.size(), outputs.data());
        return;
    }
    if (!m_maps_ready) throw_error("the learned maps exist only after the matching phase");
    TDF_CHECK(!m_derived_released);  // the maps' mip levels are gone until restore_derived_state()
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
    std::vector<std::size_t> hits;
    list_hits(g, hits);
    TDF_CHECK_EQ(hits.size(), outputs.size());
    parallel_for(hits.size(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
        for (std::size_t q = begin; q < end; ++q) {
            const std::size_t p = hits[q];
            const FieldOutputs& out = outputs[q];
            const Vec3f n_v = tangent_to_view(g, p, rot, out.normal);
            std::copy(&out.albedo.x, &out.albedo.x + 3, images.albedo.data() + 3 * p);
            std::copy(&n_v.x, &n_v.x + 3, images.view_normals.data() + 3 * p);
            images.mask.data()[p] = 1.0f;
        }
    });
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
    std::vector<std::size_t> hit_pixels;
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
        // The input at each hit, in parallel.
        list_hits(g, hit_pixels);
        TDF_CHECK_EQ(hit_pixels.size(), outputs.size());
        parallel_for(hit_pixels.size(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
            for (std::size_t q = begin; q < end; ++q) {
                const std::size_t p = hit_pixels[q];
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
            }
        });
        // The error sums in hit order, one thread: the same bits on any thread count.
        if (scored)
            for (std::size_t q = 0; q < outputs.size(); ++q) {
                const Vec3f e = outputs[q].albedo - inputs[q].albedo;
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

    measure_held_out_patches(report);
    return report;
}

// The held-out patches: tactile cosine of the learned against the target normals, and the tilt
// distances of both to the exemplar.
void Trainer::measure_held_out_patches(QualityReport& report) const {
    const RunConfig& cfg = m_config;
    GBuffer g;
    std::vector<FieldOutputs> outputs;
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
