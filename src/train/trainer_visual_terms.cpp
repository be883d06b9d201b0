// Visual loss terms on the global views (spec 5.2, 5.4): albedo matching (per pixel during
// matching, mean colour in refinement) and visual guidance on the lambertian renders.
// Reads: Batch (view G-buffers, hits and their surface, lights), the input albedo, the visual
// guidance backend.
// Writes: the loss record's visual terms, Batch::grads (d_albedo of the view hits) and, texture
// evaluation, Batch::curvature of the view hits; StageTimes::guidance; guidance frames.
#include "trainer_impl.h"

#include <tdf/core/image_ops.h>
#include <tdf/core/release.h>
#include <tdf/guidance/guidance_frames.h>
#include <tdf/guidance/relief_shading.h>
#include <tdf/guidance/schedule.h>
#include <tdf/loss/image_loss.h>
#include <tdf/render/material_sampling.h>

namespace tdf {

using namespace trainer_detail;

// ---- 4b. Visual terms on the global views (spec 5.2, 5.4) -----------------------------------
void Trainer::visual_terms(const Phase& phase, LossRecord& record) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const int B = cfg.batch_size, S = cfg.resolution;
    const bool visual_guidance = phase.visual_guidance;
    // The refinement weighs no albedo term by default (albedo_refine 0): its views then render
    // only the lambertians.
    const bool albedo_terms = phase.albedo_weight > 0;
    const std::size_t batch_values = std::size_t(B) * std::size_t(S) * std::size_t(S) * 3;
    if (albedo_terms) {  // the renders write every value of the prediction and the target
        b.size_pixel_arrays(batch_values / 3);
        parallel_fill(b.albedo_grad(), batch_values, 0.0f);
    }
    if (visual_guidance) b.shade.assign(b.hit_pixel.size(), 0.0f);
    GuidanceImages guidance_images;
    render_visual_views(albedo_terms, visual_guidance, guidance_images);
    const ImageBatchShape shape{B, S, S, 3};
    if (albedo_terms && B > 0) {
        const double value =
            phase.per_pixel_albedo
                ? mse_loss(b.albedo_pred(), b.albedo_target(), batch_values, b.albedo_grad(),
                           phase.albedo_weight)
                : mean_colour_mse_loss(b.albedo_pred(), b.albedo_target(), shape, b.albedo_grad(),
                                       phase.albedo_weight);
        record.terms[phase.per_pixel_albedo ? "albedo_matching" : "albedo_mean_colour"] = phase.albedo_weight * value;
        // Into the hits now, so the visual guidance can take the pixel arrays (the first
        // refinement iteration has both terms). Each hit's sum starts at +0 and takes the albedo
        // term, then the lambertian's: the bits of adding their sum at once.
        add_view_gradient(b.albedo_grad(), false);
    }
    if (visual_guidance && B > 0) {
        visual_guidance_terms(phase, std::move(guidance_images), record);
        add_view_gradient(b.lambertian_grad(), true);
    }
    if (texture_space()) set_view_curvature(phase);
}

// The views at the output size: the learned albedo, the input's, and with visual guidance the
// lambertian renders of both and the guidance's control images (normals, masks, surfaces).
void Trainer::render_visual_views(bool albedo_terms, bool visual_guidance, GuidanceImages& guidance_images) {
    const RunConfig& cfg = m_config;
    const TriangleMesh& mesh = *m_target.mesh;
    Batch& b = *m_batch;
    const int P = cfg.patch_batch_size, B = cfg.batch_size, S = cfg.resolution;
    const std::size_t view_values = std::size_t(S) * std::size_t(S) * 3;
    std::vector<Image>& controls = guidance_images.controls;
    std::vector<Image>& masks = guidance_images.masks;
    std::vector<Image>& surfaces = guidance_images.surfaces;
    for (int k = 0; k < B; ++k) {
        const std::size_t gi = std::size_t(P + k);
        const GBuffer& g = b.gbuffers[gi];
        const std::vector<int>& point_of = b.point_of[gi];
        const VisualView& view = b.views[std::size_t(k)];
        const bool resized = g.width != S || g.height != S;
        // Renders composited on white at the internal size, then resized to S x S (spec 3.8).
        const auto render_internal = [&](auto&& colour_of_hit, float* out) {
            // Without SSAA the internal size is the output size: rendered in place.
            if (resized && (b.internal.width() != g.width || b.internal.height() != g.height))
                b.internal = Image(g.width, g.height, 3);
            float* image = resized ? b.internal.data() : out;
            parallel_for(g.pixel_count(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
                for (std::size_t p = begin; p < end; ++p) {
                    const int q = point_of[p];
                    const Vec3f c = q < 0 ? Vec3f{1.0f, 1.0f, 1.0f} : colour_of_hit(p, std::size_t(q));  // white background
                    std::copy(&c.x, &c.x + 3, image + 3 * p);
                }
            });
            if (resized) copy_into(resize_bilinear(b.internal, S, S), out);
        };
        // The input's albedo: in texture space its bake over the atlas, sampled exactly as the learned
        // map is (same taps), so the learned map at its start renders identical images and only
        // what guidance asks for changes it; per pixel, the material itself (spec 3.1 step 5).
        const auto input_albedo = [&](std::size_t p, std::size_t q) {
            if (!texture_space()) return sample_albedo(*m_target.material, mesh, g, p, true);
            return b.target[q];
        };
        if (albedo_terms) {
            render_internal([&](std::size_t, std::size_t q) { return b.outputs[q].albedo; },
                            b.albedo_pred() + std::size_t(k) * view_values);
            render_internal(input_albedo, b.albedo_target() + std::size_t(k) * view_values);
        }
        if (visual_guidance) {
            const Vec3f light = b.lights[std::size_t(k)];
            const ViewRotation rot = view_rotation(view.camera);
            // One pass over the internal pixels for everything the guidance reads: the lambertian
            // of the learned maps and of the input (white background), the learned relief's
            // view-space normals, the coverage, the mesh's own normals (zero background). The
            // shading normal is composed once and serves the shade and the control image.
            // Every value is written below.
            const Image::Uninitialized unfilled;
            Image rendered(g.width, g.height, 3, unfilled), reference(g.width, g.height, 3, unfilled);
            Image normals(g.width, g.height, 3, unfilled), mask(g.width, g.height, 1, unfilled),
                surface(g.width, g.height, 3, unfilled);
            parallel_for(g.pixel_count(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
                for (std::size_t p = begin; p < end; ++p) {
                    const int q = point_of[p];
                    if (q < 0) {
                        std::fill_n(rendered.data() + 3 * p, 3, 1.0f);
                        std::fill_n(reference.data() + 3 * p, 3, 1.0f);
                        std::fill_n(normals.data() + 3 * p, 3, 0.0f);
                        std::fill_n(surface.data() + 3 * p, 3, 0.0f);
                        mask.data()[p] = 0.0f;
                        continue;
                    }
                    const std::size_t h = std::size_t(q);
                    // The shading normal is detached (spec 3.4): only the albedo gets gradient.
                    const Vec3f n_s = compose_shading_normal(frame_at(g, p), b.outputs[h].normal);
                    b.shade[h] = training_shade(n_s, light, g.position[p]);
                    const Vec3f lit = lambertian(b.outputs[h].albedo, b.shade[h]);
                    const Vec3f input = lambertian(input_albedo(p, h), b.shade[h]);
                    const Vec3f n_v = view_space_normal(rot, n_s);
                    const Vec3f s_v = view_space_normal(rot, g.normal[p]);
                    std::copy(&lit.x, &lit.x + 3, rendered.data() + 3 * p);
                    std::copy(&input.x, &input.x + 3, reference.data() + 3 * p);
                    std::copy(&n_v.x, &n_v.x + 3, normals.data() + 3 * p);
                    std::copy(&s_v.x, &s_v.x + 3, surface.data() + 3 * p);
                    mask.data()[p] = 1.0f;
                }
            });
            // At the output size (spec 3.8): the loss's and the request's images.
            const auto output = [&](Image& internal) {
                return resized ? resize_bilinear(internal, S, S) : std::move(internal);
            };
            guidance_images.lambertians.push_back(output(rendered));
            guidance_images.references.push_back(output(reference));
            controls.push_back(to_bae_control(output(normals)));
            masks.push_back(output(mask));
            surfaces.push_back(output(surface));
        }
    }
}

// Visual guidance (spec 5.4): the backend refines the lambertian renders; the loss pulls them
// towards the refined images (background forced to white).
void Trainer::visual_guidance_terms(const Phase& phase, GuidanceImages guidance_images, LossRecord& record) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const int B = cfg.batch_size, S = cfg.resolution;
    const std::size_t view_values = std::size_t(S) * std::size_t(S) * 3;
    const ImageBatchShape shape{B, S, S, 3};
    const auto g0 = Clock::now();
    GuidanceRequest request;
    request.kind = GuidanceKind::Visual;
    request.prompt = m_target.prompt;
    request.negative_prompt = kNegativePrompt;
    request.strength = visual_guidance_strength(phase.i, cfg.init_iterations, cfg.iterations);
    request.iteration = phase.i;
    request.seed = m_seed ^ (std::uint64_t(phase.i) << 20) ^ 0x5649u;
    request.images = std::move(guidance_images.lambertians);
    request.reference_images = std::move(guidance_images.references);
    request.control = std::move(guidance_images.controls);
    request.masks = std::move(guidance_images.masks);
    request.surface_normals = std::move(guidance_images.surfaces);
    GuidanceResult result = m_visual_guidance->refine(request);
    validate_result(request, result, m_visual_guidance->name());
    if (!m_frames_folder.empty()) save_guidance_frames(m_frames_folder, phase.i, request, result);
    // The loss reads the renders and the refined images each as one array over the views.
    const std::size_t batch_values = std::size_t(B) * view_values;
    b.size_pixel_arrays(batch_values / 3);
    float* const lambertian = b.lambertian();
    float* const refined = b.refined_lambertian();
    float* const grad = b.lambertian_grad();
    for (int k = 0; k < B; ++k)
        parallel_copy(request.images[std::size_t(k)].data(), view_values,
                      lambertian + std::size_t(k) * view_values);
    release(request.images, request.reference_images, request.control, request.surface_normals);
    parallel_fill(grad, batch_values, 0.0f);
    for (int k = 0; k < B; ++k) {
        // Background forced to white (spec 5.4).
        const float* r = result.refined[std::size_t(k)].data();
        const float* m = request.masks[std::size_t(k)].data();
        float* out = refined + std::size_t(k) * view_values;
        parallel_for(view_values / 3, kPixelGrain, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p)
                for (int c = 0; c < 3; ++c) out[3 * p + c] = m[p] == 0.0f ? 1.0f : r[3 * p + c];
        });
    }
    const float w = cfg.weights.visual_guidance, ws = cfg.weights.visual_guidance_structural;
    if (cfg.visual_guidance_loss == "mse") {
        record.terms["visual_guidance_mse"] = w * mse_loss(lambertian, refined, batch_values, grad, w);
    } else {
        const double l1 = l1_loss(lambertian, refined, batch_values, grad, w);
        const double structural = ws > 0 ? ssim_loss(lambertian, refined, shape, grad, w * ws) : 0.0;
        record.terms["visual_guidance_l1"] = w * l1;
        record.terms["visual_guidance_structural"] = w * ws * structural;
    }
    m_times.guidance += seconds_since(g0);
}

// One image gradient of the views (B x S x S x 3 at the output size: the albedo term's, or with
// `lambertian` the lambertian's, times each hit's shade) back through the resize (its adjoint) to
// the internal pixels, then added to the hits' albedo gradients.
void Trainer::add_view_gradient(const float* grad, bool lambertian) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const int P = cfg.patch_batch_size, B = cfg.batch_size, S = cfg.resolution;
    const std::size_t view_values = std::size_t(S) * std::size_t(S) * 3;
    for (int k = 0; k < B; ++k) {
        const std::size_t gi = std::size_t(P + k);
        const GBuffer& g = b.gbuffers[gi];
        const std::vector<int>& point_of = b.point_of[gi];
        // Without SSAA the view's pixels are the internal ones: read in place.
        const float* view = grad + std::size_t(k) * view_values;
        Image internal;
        if (g.width != S || g.height != S) {
            Image output(S, S, 3, Image::Uninitialized{});  // every value copied next
            std::copy_n(view, view_values, output.data());
            internal = resize_bilinear_adjoint(output, g.width, g.height);
            view = internal.data();
        }
        parallel_for(g.pixel_count(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p) {
                const int q = point_of[p];
                if (q < 0) continue;
                const float* v = view + 3 * p;
                const Vec3f d{v[0], v[1], v[2]};
                b.grads[std::size_t(q)].d_albedo += lambertian ? lambertian_backward(b.shade[std::size_t(q)], d) : d;
            }
        });
    }
}

// Texture evaluation: the view hits' Jacobi curvature. Per value, 2 w / N for squared errors (an
// L1 term counts as a squared error at a 0.1 scale), spread over the internal pixels as the
// resize spreads the gradients.
void Trainer::set_view_curvature(const Phase& phase) {
    const RunConfig& cfg = m_config;
    Batch& b = *m_batch;
    const int P = cfg.patch_batch_size, B = cfg.batch_size, S = cfg.resolution;
    const bool visual_guidance = phase.visual_guidance;
    const double values = double(B) * double(S) * double(S) * 3.0;
    for (int k = 0; k < B; ++k) {
        const std::size_t gi = std::size_t(P + k);
        const GBuffer& g = b.gbuffers[gi];
        const std::vector<int>& point_of = b.point_of[gi];
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
                const double shade = visual_guidance ? double(b.shade[std::size_t(q)]) : 0.0;
                b.curvature[std::size_t(q)] = float(albedo_kappa + lambertian_kappa * shade * shade);
            }
        });
    }
}

}  // namespace tdf
