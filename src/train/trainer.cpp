#include <tdf/train/trainer.h>

#include <tdf/atlas/uv_metrics.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/guidance/guidance_frames.h>
#include <tdf/guidance/relief_shading.h>
#include <tdf/guidance/schedule.h>
#include <tdf/loss/image_loss.h>
#include <tdf/loss/shading_grad.h>
#include <tdf/loss/tactile_loss.h>
#include <tdf/render/resample.h>
#include <tdf/render/shading.h>
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

ViewRotation view_rotation(const Camera& c) { return {c.right, c.up, c.back}; }

TangentFrame frame_at(const GBuffer& g, std::size_t i) { return {g.tangent[i], g.normal[i], g.handedness[i]}; }

// The target tactile normal of a hit pixel as the training renderer builds it: sampled over the
// whole pyramid, renormalised (spec 3.1 step 5), in tangent space ...
Vec3f target_tangent_normal(const TrainingTarget& t, const GBuffer& g, std::size_t i) {
    return safe_normalize(sample_tactile(*t.material, g, i, -1, t.tactile_layout));
}

// ... and composed with the pixel's frame, in view space.
Vec3f tangent_to_view(const GBuffer& g, std::size_t i, const ViewRotation& r, Vec3f tangent_normal) {
    return view_space_normal(r, compose_shading_normal(frame_at(g, i), tangent_normal));
}

Vec3f target_view_normal(const TrainingTarget& t, const GBuffer& g, std::size_t i, const ViewRotation& r) {
    return tangent_to_view(g, i, r, target_tangent_normal(t, g, i));
}

void copy_into(const Image& image, float* out) { std::copy(image.values().begin(), image.values().end(), out); }

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
    std::vector<float> shade;  // per point: the lambertian shade of visual hits
    Image internal;            // one view at its internal (SSAA) size
};

namespace {

/// sqrt(3-D area / UV area): the mean surface length of one UV unit.
double mesh_units_per_uv_unit(const TriangleMesh& mesh) {
    double area_3d = 0, area_uv = 0;
    for (std::size_t f = 0; f < mesh.triangles.size() && mesh.has_uvs(); ++f) {
        const Vec3i& t = mesh.triangles[f];
        const Vec3i& u = mesh.uv_triangles[f];
        area_3d += triangle_area(mesh.positions[std::size_t(t.x)], mesh.positions[std::size_t(t.y)],
                                 mesh.positions[std::size_t(t.z)]);
        area_uv += 0.5 * std::fabs(signed_uv_area2(mesh.uvs[std::size_t(u.x)], mesh.uvs[std::size_t(u.y)],
                                                   mesh.uvs[std::size_t(u.z)]));
    }
    if (!(area_uv > 0) || !(area_3d > 0)) throw_error("{}: the UV atlas has no area", mesh.source_path);
    return std::sqrt(area_3d / area_uv);
}

}  // namespace

float physical_tactile_uv_scale(const TriangleMesh& mesh, float mm_per_unit, int map_width_pixels,
                                float mm_per_pixel) {
    const double uv_mm = mesh_units_per_uv_unit(mesh) * double(mm_per_unit);
    return float(uv_mm / (double(map_width_pixels) * double(mm_per_pixel)));
}

float patch_pixels_per_texel(const TrainingTarget& target, const RunConfig& config) {
    const MipTexture* map = target.material->tactile;
    if (!map || map->empty() || !target.mesh->has_uvs()) return 0.0f;
    const double texels_per_uv_unit = std::sqrt(double(map->width()) * double(map->height())) * target.tactile_layout.uv_scale;
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
    m_field = std::make_unique<TextureField>(field_config, FieldDomain{bounds.lower, bounds.upper}, seed);
    AdamHyperparams hyper;
    hyper.learning_rate = config.learning_rate;
    m_adam = std::make_unique<Adam>(m_field->parameter_count(), hyper);
    m_gradient.assign(m_field->parameter_count(), 0.0f);
}

Trainer::~Trainer() = default;

void Trainer::set_guidance(std::unique_ptr<GuidanceBackend> visual, std::unique_ptr<GuidanceBackend> tactile) {
    if (visual && !visual->supports(GuidanceKind::Visual))
        throw_error("guidance backend '{}' cannot do visual guidance", visual->name());
    if (tactile && !tactile->supports(GuidanceKind::Tactile))
        throw_error("guidance backend '{}' cannot do tactile guidance", tactile->name());
    m_visual_guidance = std::move(visual);
    m_tactile_guidance = std::move(tactile);
}

void Trainer::restore(int iteration, const std::vector<float>& parameters, const AdamState& adam) {
    if (parameters.size() != m_field->parameter_count())
        throw_error("checkpoint has {} field parameters, this configuration needs {}", parameters.size(),
                    m_field->parameter_count());
    m_field->parameters() = parameters;
    m_adam->restore(adam);
    m_iteration = iteration;
}

LossRecord Trainer::step() {
    const RunConfig& cfg = m_config;
    const TriangleMesh& mesh = *m_target.mesh;
    Batch& b = *m_batch;
    const int i = m_iteration;
    const auto iteration_start = Clock::now();
    Rng rng = Rng::stream(m_seed, std::uint64_t(i));

    // Phase table of spec 5.1 (i is the 0-based loop index).
    const bool per_pixel_albedo = i <= cfg.init_iterations;
    const float albedo_weight = per_pixel_albedo ? cfg.weights.albedo_init : cfg.weights.albedo_refine;
    const float tactile_weight = i < cfg.init_iterations ? cfg.weights.tactile_init : cfg.weights.tactile_refine;
    const bool visual_guidance = m_visual_guidance && i >= cfg.init_iterations && cfg.weights.visual_guidance > 0;
    const bool tactile_guidance = m_tactile_guidance && i > cfg.init_iterations && cfg.weights.tactile_guidance > 0;

    // ---- 1. Cameras and tracing ------------------------------------------------------------
    auto t0 = Clock::now();
    const int P = cfg.patch_batch_size, B = cfg.batch_size, R = cfg.patch_resolution, S = cfg.resolution;
    b.cameras.resize(std::size_t(P + B));
    b.gbuffers.resize(std::size_t(P + B));
    b.views.resize(std::size_t(B));
    b.lights.resize(std::size_t(B));
    for (int k = 0; k < P; ++k) b.cameras[std::size_t(k)] =
            sample_patch_view(rng, mesh, R, cfg.patch_distance, cfg.patch_half_extent);
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
    }
    for (std::size_t k = 0; k < b.cameras.size(); ++k)
        trace_gbuffer(*m_target.scene, mesh, b.cameras[k], b.gbuffers[k]);

    // Gather hit points (background pixels need no field evaluation, spec 13.18).
    b.point_of.resize(b.gbuffers.size());
    b.points.clear();
    for (std::size_t k = 0; k < b.gbuffers.size(); ++k) {
        const GBuffer& g = b.gbuffers[k];
        std::vector<int>& point_of = b.point_of[k];
        point_of.resize(g.pixel_count());
        for (std::size_t p = 0; p < g.pixel_count(); ++p) {
            if (g.mask[p] > 0.0f) {
                point_of[p] = int(b.points.size());
                b.points.push_back(g.position[p]);
            } else {
                point_of[p] = -1;
            }
        }
    }
    const std::size_t n = b.points.size();
    m_times.tracing += seconds_since(t0);

    // ---- 2. Field forward --------------------------------------------------------------------
    t0 = Clock::now();
    b.outputs.resize(n);
    m_field->evaluate(b.points.data(), n, b.outputs.data(), b.field_cache);
    b.grads.assign(n, FieldOutputGrads{});
    m_times.field_forward += seconds_since(t0);

    LossRecord record;
    record.iteration = i;
    double guidance_seconds = 0;
    t0 = Clock::now();

    // ---- 3. Tactile terms on patch view-space shading normals (spec 5.3, 5.5) ----------------
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
                target[p] = target_view_normal(m_target, g, p, rot);
            }
        });
    }
    if (tactile_weight > 0 && P > 0)
        record.terms["tactile_matching"] =
            tactile_weight * tactile_matching_loss(b.patch_pred.data(), b.patch_target.data(), b.patch_pred.size(),
                                                   b.patch_grad.data(), tactile_weight);
    if (tactile_guidance && P > 0) {
        const auto g0 = Clock::now();
        GuidanceRequest request;
        request.kind = GuidanceKind::Tactile;
        request.prompt = "sks normal map";  // spec 5.5
        request.strength = kTactileGuidanceStrength;
        request.iteration = i;
        request.seed = m_seed ^ (std::uint64_t(i) << 20);
        request.pixels_per_texel = m_patch_pixels_per_texel;
        for (int k = 0; k < P; ++k) {
            const GBuffer& g = b.gbuffers[std::size_t(k)];
            const ViewRotation rot = view_rotation(b.cameras[std::size_t(k)]);
            Image normals(R, R, 3), mask(R, R, 1), surface_normals(R, R, 3), surface_tangents(R, R, 4);
            const Vec3f* pred = b.patch_pred.data() + std::size_t(k) * patch_pixels;
            for (std::size_t p = 0; p < patch_pixels; ++p) {
                std::copy(&pred[p].x, &pred[p].x + 3, normals.data() + 3 * p);
                mask.data()[p] = g.mask[p];
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
        const GuidanceResult result = m_tactile_guidance->refine(request);
        validate_result(request, result, m_tactile_guidance->name());
        if (!m_frames_folder.empty()) save_guidance_frames(m_frames_folder, i, request, result);
        std::vector<Vec3f> refined(b.patch_pred.size());
        for (int k = 0; k < P; ++k)
            std::copy_n(result.refined[std::size_t(k)].data(), 3 * patch_pixels,
                        &refined[std::size_t(k) * patch_pixels].x);
        const TactileGuidanceMetric metric = cfg.tactile_guidance_loss == TactileGuidanceLoss::Cosine
                                                 ? TactileGuidanceMetric::Cosine
                                                 : TactileGuidanceMetric::Mse;
        const float w = cfg.weights.tactile_guidance;
        record.terms["tactile_guidance"] =
            w * tactile_guidance_loss(metric, b.patch_pred.data(), refined.data(), refined.size(), b.patch_grad.data(), w);
        guidance_seconds += seconds_since(g0);
    }
    // Back through the view rotation and the TBN composition to the field's normal output.
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

    // ---- 4. Visual terms on the global views (spec 5.2, 5.4) ----------------------------------
    const std::size_t view_values = std::size_t(S) * std::size_t(S) * 3;
    b.albedo_pred.resize(std::size_t(B) * view_values);
    b.albedo_target.resize(b.albedo_pred.size());
    b.albedo_grad.assign(b.albedo_pred.size(), 0.0f);
    if (visual_guidance) {
        b.lambertian.resize(b.albedo_pred.size());
        b.lambertian_grad.assign(b.albedo_pred.size(), 0.0f);
        b.shade.assign(n, 0.0f);
    }
    std::vector<Image> controls, masks;
    for (int k = 0; k < B; ++k) {
        const std::size_t gi = std::size_t(P + k);
        const GBuffer& g = b.gbuffers[gi];
        const std::vector<int>& point_of = b.point_of[gi];
        const VisualView& view = b.views[std::size_t(k)];
        const bool resized = g.width != S || g.height != S;
        // Renders composited on white at the internal size, then resized to S x S (spec 3.8).
        const auto render_internal = [&](auto&& colour_of_hit, float* out) {
            if (b.internal.width() != g.width || b.internal.height() != g.height)
                b.internal = Image(g.width, g.height, 3);
            std::fill(b.internal.values().begin(), b.internal.values().end(), 1.0f);  // white background
            parallel_for(g.pixel_count(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
                for (std::size_t p = begin; p < end; ++p) {
                    const int q = point_of[p];
                    if (q < 0) continue;
                    const Vec3f c = colour_of_hit(p, std::size_t(q));
                    std::copy(&c.x, &c.x + 3, b.internal.data() + 3 * p);
                }
            });
            copy_into(resized ? downsample_bilinear(b.internal, S, S) : b.internal, out);
        };
        float* pred = b.albedo_pred.data() + std::size_t(k) * view_values;
        render_internal([&](std::size_t, std::size_t q) { return b.outputs[q].albedo; }, pred);
        render_internal([&](std::size_t p, std::size_t) { return sample_albedo(*m_target.material, mesh, g, p, true); },
                        b.albedo_target.data() + std::size_t(k) * view_values);
        if (visual_guidance) {
            const Vec3f light = b.lights[std::size_t(k)];
            const ViewRotation rot = view_rotation(view.camera);
            render_internal(
                [&](std::size_t p, std::size_t q) {
                    // The shading normal is detached (spec 3.4): only the albedo gets gradient.
                    const Vec3f n_s = compose_shading_normal(frame_at(g, p), b.outputs[q].normal);
                    b.shade[q] = lambert_shade(n_s, light, g.position[p]);
                    return lambertian(b.outputs[q].albedo, b.shade[q]);
                },
                b.lambertian.data() + std::size_t(k) * view_values);
            Image control(S, S, 3), mask(S, S, 1);
            Image normals_internal(g.width, g.height, 3, 0.0f), mask_internal(g.width, g.height, 1, 0.0f);
            for (std::size_t p = 0; p < g.pixel_count(); ++p) {
                const int q = point_of[p];
                if (q < 0) continue;
                const Vec3f n_v = tangent_to_view(g, p, rot, b.outputs[std::size_t(q)].normal);
                std::copy(&n_v.x, &n_v.x + 3, normals_internal.data() + 3 * p);
                mask_internal.data()[p] = 1.0f;
            }
            controls.push_back(to_bae_control(resized ? downsample_bilinear(normals_internal, S, S) : normals_internal));
            masks.push_back(resized ? downsample_bilinear(mask_internal, S, S) : mask_internal);
        }
    }
    const ImageBatchShape shape{B, S, S, 3};
    if (albedo_weight > 0 && B > 0) {
        const double value =
            per_pixel_albedo
                ? mse_loss(b.albedo_pred.data(), b.albedo_target.data(), b.albedo_pred.size(), b.albedo_grad.data(),
                           albedo_weight)
                : mean_colour_mse_loss(b.albedo_pred.data(), b.albedo_target.data(), shape, b.albedo_grad.data(),
                                       albedo_weight);
        record.terms[per_pixel_albedo ? "albedo_matching" : "albedo_mean_colour"] = albedo_weight * value;
    }
    if (visual_guidance && B > 0) {
        const auto g0 = Clock::now();
        GuidanceRequest request;
        request.kind = GuidanceKind::Visual;
        request.prompt = m_target.prompt;
        request.negative_prompt = kNegativePrompt;
        request.strength = visual_guidance_strength(i, cfg.init_iterations, cfg.iterations);
        request.iteration = i;
        request.seed = m_seed ^ (std::uint64_t(i) << 20) ^ 0x5649u;
        for (int k = 0; k < B; ++k) {
            Image image(S, S, 3);
            std::copy_n(b.lambertian.data() + std::size_t(k) * view_values, view_values, image.data());
            request.images.push_back(std::move(image));
        }
        request.control = std::move(controls);
        request.masks = std::move(masks);
        GuidanceResult result = m_visual_guidance->refine(request);
        validate_result(request, result, m_visual_guidance->name());
        if (!m_frames_folder.empty()) save_guidance_frames(m_frames_folder, i, request, result);
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
        const double l1 = l1_loss(b.lambertian.data(), refined.data(), refined.size(), b.lambertian_grad.data(), w);
        const double structural = ws > 0 ? ssim_loss(b.lambertian.data(), refined.data(), shape,
                                                      b.lambertian_grad.data(), w * ws)
                                          : 0.0;
        record.terms["visual_guidance_l1"] = w * l1;
        record.terms["visual_guidance_structural"] = w * ws * structural;
        guidance_seconds += seconds_since(g0);
    }
    // Back through the resize (its adjoint) to the internal pixels, then to the field's albedo.
    for (int k = 0; k < B; ++k) {
        const std::size_t gi = std::size_t(P + k);
        const GBuffer& g = b.gbuffers[gi];
        const std::vector<int>& point_of = b.point_of[gi];
        const bool resized = g.width != S || g.height != S;
        const auto to_internal = [&](const std::vector<float>& grad) {
            Image out(S, S, 3);
            std::copy_n(grad.data() + std::size_t(k) * view_values, view_values, out.data());
            return resized ? downsample_bilinear_adjoint(out, g.width, g.height) : out;
        };
        const Image albedo_grad = to_internal(b.albedo_grad);
        const Image lambertian_grad = visual_guidance ? to_internal(b.lambertian_grad) : Image();
        parallel_for(g.pixel_count(), kPixelGrain, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p) {
                const int q = point_of[p];
                if (q < 0) continue;
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
    m_times.guidance += guidance_seconds;
    m_times.losses += seconds_since(t0) - guidance_seconds;

    double total = 0;
    for (const auto& [name, value] : record.terms) {
        if (!std::isfinite(value))
            throw_error("iteration {}: loss term '{}' is not finite ({}); the field was not updated", i, name, value);
        total += value;
    }
    record.terms["total"] = total;

    // ---- 5. Backward and Adam -----------------------------------------------------------------
    t0 = Clock::now();
    std::fill(m_gradient.begin(), m_gradient.end(), 0.0f);
    m_field->backward(b.points.data(), b.grads.data(), n, m_gradient, b.field_cache);
    m_times.field_backward += seconds_since(t0);
    for (float g : m_gradient)
        if (!std::isfinite(g)) throw_error("iteration {}: the field gradient is not finite; the field was not updated", i);
    t0 = Clock::now();
    m_adam->step(m_field->parameters(), m_gradient);
    m_times.adam += seconds_since(t0);

    ++m_iteration;
    record.seconds = seconds_since(iteration_start);
    return record;
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

void Trainer::trace_and_evaluate(const Camera& camera, GBuffer& g, std::vector<FieldOutputs>& outputs) const {
    trace_gbuffer(*m_target.scene, *m_target.mesh, camera, g);
    std::vector<Vec3f> points;
    for (std::size_t p = 0; p < g.pixel_count(); ++p)
        if (g.mask[p] > 0.0f) points.push_back(g.position[p]);
    outputs.resize(points.size());
    m_field->evaluate(points.data(), points.size(), outputs.data());
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
    double squared = 0, max_error = 0, alignment = 0;
    std::size_t values_fg = 0, values_full = 0;
    GBuffer g;
    std::vector<FieldOutputs> outputs;
    for (int k = 0; k < cfg.held_out_views; ++k) {
        const Camera camera = held_out_view(k);
        trace_and_evaluate(camera, g, outputs);
        values_full += 3 * g.pixel_count();  // background: white in both, zero error (spec 5.2)
        std::size_t q = 0;
        for (std::size_t p = 0; p < g.pixel_count(); ++p) {
            if (g.mask[p] <= 0.0f) continue;
            const Vec3f e = outputs[q++].albedo - sample_albedo(*m_target.material, mesh, g, p, true);
            for (int c = 0; c < 3; ++c) {
                squared += double(e[c]) * e[c];
                max_error = std::max(max_error, double(std::fabs(e[c])));
            }
            values_fg += 3;
        }
        const LearnedImages learned = learned_images(camera, g, outputs);
        alignment += colour_geometry_correlation(learned.albedo, learned.view_normals, learned.mask);
    }
    const auto psnr = [](double sum, std::size_t count) {
        if (count == 0) return 0.0;
        const double mse = sum / double(count);
        return mse > 0 ? 10.0 * std::log10(1.0 / mse) : 99.0;
    };
    report.albedo_psnr_foreground = psnr(squared, values_fg);
    report.albedo_psnr_full = psnr(squared, values_full);
    report.albedo_max_error = max_error;
    report.colour_geometry_correlation = cfg.held_out_views > 0 ? alignment / cfg.held_out_views : 0.0;
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
            const Vec3f target = target_tangent_normal(m_target, g, p);
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
            {"tactile_tilt_distance", tactile_tilt_distance},
            {"target_tilt_distance", target_tilt_distance},
            {"held_out_views", views},
            {"held_out_patches", patches}};
}

Json StageTimes::to_json(int iterations) const {
    const double n = std::max(iterations, 1);
    return {{"tracing", tracing / n},     {"field_forward", field_forward / n}, {"losses", losses / n},
            {"guidance", guidance / n},   {"field_backward", field_backward / n}, {"adam", adam / n},
            {"iterations", iterations}};
}

}  // namespace tdf
