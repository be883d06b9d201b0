// Tactile loss terms on the patches (spec 5.3, 5.5): matching against the target normals and
// tactile guidance, single-part or gated per part.
// Reads: Batch (patch G-buffers, hits and their surface), the tactile target, the guidance
// backends or the part gate.
// Writes: the loss record's tactile terms, Batch::grads (d_normal of the patch hits) and, texture
// evaluation, Batch::curvature of the patch hits; StageTimes::guidance; guidance frames.
#include "trainer_impl.h"

#include <tdf/guidance/guidance_frames.h>
#include <tdf/guidance/schedule.h>
#include <tdf/loss/tactile_loss.h>
#include <tdf/train/part_gating.h>

namespace tdf {

using namespace trainer_detail;

namespace {

// Appends one patch to a tactile guidance request: its rendered view-space normals `pred`, its
// coverage (times `weight` per pixel when given: a part's mask) and its surface frames.
void add_patch_to_request(GuidanceRequest& request, const GBuffer& g, const Camera& camera, const Vec3f* pred,
                          const float* weight) {
    const int w = g.width, h = g.height;
    const ViewRotation rot = view_rotation(camera);
    // Every value is written below (zero off the surface).
    const Image::Uninitialized unfilled;
    Image normals(w, h, 3, unfilled), mask(w, h, 1, unfilled), surface_normals(w, h, 3, unfilled),
        surface_tangents(w, h, 4, unfilled);
    parallel_for(g.pixel_count(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p < end; ++p) {
            std::copy(&pred[p].x, &pred[p].x + 3, normals.data() + 3 * p);
            mask.data()[p] = weight ? g.mask[p] * weight[p] : g.mask[p];
            const bool hit = g.mask[p] > 0.0f;
            const Vec3f normal = hit ? view_space_normal(rot, g.normal[p]) : Vec3f{};
            const Vec3f tangent = hit ? view_space_normal(rot, g.tangent[p]) : Vec3f{};
            std::copy(&normal.x, &normal.x + 3, surface_normals.data() + 3 * p);
            std::copy(&tangent.x, &tangent.x + 3, surface_tangents.data() + 4 * p);
            surface_tangents.data()[4 * p + 3] = hit ? g.handedness[p] : 0.0f;
        }
    });
    request.images.push_back(std::move(normals));
    request.masks.push_back(std::move(mask));
    request.surface_normals.push_back(std::move(surface_normals));
    request.surface_tangents.push_back(std::move(surface_tangents));
}

}  // namespace

// ---- 4a. Tactile terms on patch view-space shading normals (spec 5.3, 5.5) -----------------
void Trainer::tactile_terms(const Phase& phase, LossRecord& record) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const int P = cfg.patch_batch_size, R = cfg.patch_resolution;
    const std::size_t patch_pixels = std::size_t(R) * std::size_t(R);
    b.size_pixel_arrays(std::size_t(P) * patch_pixels);
    parallel_fill(b.patch_grad(), b.pixel_array_size(), Vec3f{});
    for (int k = 0; k < P; ++k) {
        const GBuffer& g = b.gbuffers[std::size_t(k)];
        const ViewRotation rot = view_rotation(b.cameras[std::size_t(k)]);
        const std::vector<int>& point_of = b.point_of[std::size_t(k)];
        Vec3f* pred = b.patch_pred() + std::size_t(k) * patch_pixels;
        Vec3f* target = b.patch_target() + std::size_t(k) * patch_pixels;
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
                target[p] = texture_space() ? tangent_to_view(g, p, rot, b.target[std::size_t(q)])
                                            : target_view_normal(m_target, g, p, rot);
            }
        });
    }
    if (m_part_gate) {
        gated_tactile_terms(phase, record);
    } else if (phase.tactile_weight > 0 && P > 0) {
        record.terms["tactile_matching"] =
            phase.tactile_weight * tactile_matching_loss(b.patch_pred(), b.patch_target(),
                                                         b.pixel_array_size(), b.patch_grad(),
                                                         phase.tactile_weight);
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
                                 b.patch_pred() + std::size_t(k) * patch_pixels, nullptr);
        const GuidanceResult result = m_tactile_guidance->refine(request);
        validate_result(request, result, m_tactile_guidance->name());
        if (!m_frames_folder.empty()) save_guidance_frames(m_frames_folder, phase.i, request, result);
        // Into the target's array: the matching term has read it.
        Vec3f* refined = b.patch_target();
        for (int k = 0; k < P; ++k)
            parallel_copy(result.refined[std::size_t(k)].data(), 3 * patch_pixels,
                          &refined[std::size_t(k) * patch_pixels].x);
        const TactileGuidanceMetric metric = cfg.tactile_guidance_loss == TactileGuidanceLoss::Cosine
                                                 ? TactileGuidanceMetric::Cosine
                                                 : TactileGuidanceMetric::Mse;
        const float w = cfg.weights.tactile_guidance;
        record.terms["tactile_guidance"] =
            w * tactile_guidance_loss(metric, b.patch_pred(), refined, b.pixel_array_size(), b.patch_grad(),
                                      w);
        m_times.guidance += seconds_since(g0);
    }
    if (texture_space() && !m_part_gate) {
        // 1 - cos has unit curvature across the unit sphere; MSE on 3 components 2 / 3 per value.
        const double pixels = double(P) * double(patch_pixels);
        double kappa = phase.tactile_weight > 0 ? double(phase.tactile_weight) / pixels : 0.0;
        if (phase.tactile_guidance)
            kappa += double(cfg.weights.tactile_guidance) / pixels *
                     (cfg.tactile_guidance_loss == TactileGuidanceLoss::Cosine ? 1.0 : 2.0 / 3.0);
        for (int k = 0; k < P; ++k) {
            const std::vector<int>& point_of = b.point_of[std::size_t(k)];
            parallel_for(point_of.size(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
                for (std::size_t p = begin; p < end; ++p)
                    if (point_of[p] >= 0) b.curvature[std::size_t(point_of[p])] = float(kappa);
            });
        }
    }
    // Back through the view rotation and the TBN composition to the surface's tangent normal.
    for (int k = 0; k < P; ++k) {
        const GBuffer& g = b.gbuffers[std::size_t(k)];
        const ViewRotation rot = view_rotation(b.cameras[std::size_t(k)]);
        const std::vector<int>& point_of = b.point_of[std::size_t(k)];
        const Vec3f* grad = b.patch_grad() + std::size_t(k) * patch_pixels;
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

// Multi-part (docs/multi-part-textures.md): each patch pixel's part from the gate's labels at
// its lookup, the per-part matching and guidance terms, and the Jacobi curvature per part.
void Trainer::gated_tactile_terms(const Phase& phase, LossRecord& record) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    PartGate& gate = *m_part_gate;
    const int P = cfg.patch_batch_size, R = cfg.patch_resolution;
    const std::size_t patch_pixels = std::size_t(R) * std::size_t(R);
    std::vector<std::int16_t> pixel_part(b.pixel_array_size(), -1), guidance_part(b.pixel_array_size(), -1);
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
    patches.pred = b.patch_pred();
    patches.target = b.patch_target();
    patches.part = pixel_part.data();
    patches.guidance_part = guidance_part.data();
    patches.grad = b.patch_grad();
    patches.add_patch = [&](GuidanceRequest& request, int k, const float* mask) {
        add_patch_to_request(request, b.gbuffers[std::size_t(k)], b.cameras[std::size_t(k)],
                             b.patch_pred() + std::size_t(k) * patch_pixels, mask);
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

}  // namespace tdf
