// The views of one iteration: cameras (patches, then visual views, in the order of spec 9's
// random draws), their tracing, and the surface at every hit.
// Reads: the iteration's Rng, the mesh and its Embree scene, the field or the learned maps.
// Writes: Batch::cameras, views, lights, gbuffers, point_of, the hit lists, outputs (and, texture
// evaluation, each hit's lookup uv and lod and its unnormalised normal).
#include "trainer_impl.h"

#include <tdf/scene/view_sampler.h>

namespace tdf {

using namespace trainer_detail;

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
        // In texture space the iterations look the maps up and shade: no triangle ids,
        // barycentrics or depth (field evaluation samples the input material through them).
        trace_gbuffer(*m_target.scene, *m_target.mesh, b.cameras[k], b.gbuffers[k],
                      texture_space() ? GBufferFields::Shading : GBufferFields::All);
    b.point_of.resize(b.gbuffers.size());
    std::size_t pixels = 0;
    for (std::size_t k = first; k < last; ++k) pixels += b.gbuffers[k].pixel_count();
    b.reserve_hits(pixels, texture_space());
    b.points.clear();
    b.patch_hit_count = 0;
    b.hit_pixel.clear();
    b.hit_view.clear();
    // The hits in pixel order, view after view: each chunk of pixels counts its hits, a prefix sum
    // over the chunks places them, and the chunks fill their places in parallel (2 M pixels an
    // iteration; the same lists as one pass in order).
    constexpr std::size_t kChunk = 1 << 14;
    for (std::size_t k = first; k < last; ++k) {
        if (k == patches) b.patch_hit_count = b.hit_pixel.size();
        const GBuffer& g = b.gbuffers[k];
        std::vector<int>& point_of = b.point_of[k];
        point_of.resize(g.pixel_count());
        const std::size_t chunks = chunk_count(g.pixel_count(), kChunk);
        b.chunk_hits.assign(chunks + 1, 0);
        parallel_for(chunks, 1, [&](std::size_t c_begin, std::size_t c_end) {
            for (std::size_t c = c_begin; c < c_end; ++c) {
                std::size_t hits = 0;
                for (std::size_t p = c * kChunk, end = std::min(g.pixel_count(), p + kChunk); p < end; ++p)
                    hits += g.mask[p] > 0.0f;
                b.chunk_hits[c + 1] = hits;
            }
        });
        b.chunk_hits[0] = b.hit_pixel.size();
        for (std::size_t c = 0; c < chunks; ++c) b.chunk_hits[c + 1] += b.chunk_hits[c];
        b.hit_pixel.resize(b.chunk_hits[chunks]);
        b.hit_view.resize(b.chunk_hits[chunks]);
        if (!texture_space()) b.points.resize(b.chunk_hits[chunks]);  // the field's inputs
        parallel_for(chunks, 1, [&](std::size_t c_begin, std::size_t c_end) {
            for (std::size_t c = c_begin; c < c_end; ++c) {
                std::size_t q = b.chunk_hits[c];
                for (std::size_t p = c * kChunk, end = std::min(g.pixel_count(), p + kChunk); p < end; ++p) {
                    if (!(g.mask[p] > 0.0f)) {
                        point_of[p] = -1;
                        continue;
                    }
                    point_of[p] = int(q);
                    if (!texture_space()) b.points[q] = g.position[p];
                    b.hit_pixel[q] = std::uint32_t(p);
                    b.hit_view[q] = std::uint16_t(k);
                    ++q;
                }
            }
        });
    }
    if (last <= patches) b.patch_hit_count = b.hit_pixel.size();
}

// ---- 3. The surface at every hit: field (pixel) or learned maps (texture) -------------------
void Trainer::evaluate_surface(bool with_view_normals) {
    Batch& b = *m_batch;
    const std::size_t n = b.hit_pixel.size();
    b.outputs.resize(n);
    if (!texture_space()) {
        b.grads.assign(n, FieldOutputGrads{});
        m_field->evaluate(b.points.data(), n, b.outputs.data(), b.field_cache);
        return;
    }
    const MipTexture& albedo = m_maps->albedo();
    const MipTexture& normal = m_maps->normal();
    b.lookup_uv.resize(n);
    b.lookup_lod.resize(n);
    b.raw_normal.resize(n);
    b.target.resize(n);
    b.grads.resize(n);  // zeroed below, per hit, in parallel
    b.curvature.resize(n);
    parallel_for(n, kPixelGrain, [&](std::size_t begin, std::size_t end) {
        TrilinearTaps taps;
        for (std::size_t q = begin; q < end; ++q) {
            const GBuffer& g = b.gbuffers[b.hit_view[q]];
            const std::size_t p = b.hit_pixel[q];
            b.grads[q] = FieldOutputGrads{};
            b.curvature[q] = 0.0f;
            // Both maps have the atlas's size, so one LOD serves both (spec 3.7).
            const float lod = albedo.level_of_detail(g.duv_dx[p], g.duv_dy[p]);
            b.lookup_uv[q] = g.uv[p];
            b.lookup_lod[q] = lod;
            albedo.taps(g.uv[p], lod, -1, taps);
            // Patches read only the normal map; views the albedo, and the normals only for the
            // visual guidance's shading and control images.
            const bool patch = q < b.patch_hit_count;
            if (!patch) b.outputs[q].albedo = gather3(albedo, taps);
            b.target[q] = patch ? safe_normalize(gather3(m_tactile_target_texture, taps))
                                : gather3(m_albedo_target_texture, taps);
            if (patch || with_view_normals) {
                b.raw_normal[q] = gather3(normal, taps);  // same size, same taps
                // Renormalised per pixel as the training renderer does with its maps (spec 3.1 step 5).
                b.outputs[q].normal = safe_normalize(b.raw_normal[q]);
            }
        }
    });
}

}  // namespace tdf
