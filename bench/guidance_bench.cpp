// Cost of the built-in guidance backends (the reference refines 4 patches and 1-4 views per
// iteration, spec 5.4-5.5):
//  - BM_ExemplarPatchMatch / BM_ReliefShading: one image of the given size, searched at full
//    size (no surface frames, pixels_per_texel unknown), as the earlier measurements were.
//  - BM_TactileRefinementIteration / BM_VisualRefinementIteration / BM_GuidancePerRefinementIteration:
//    one whole refinement-iteration request at the main job's sizes (`tdf optimize` on
//    scenes/pebble_sphere at defaults): 4 tactile patches of 512x512 with surface frames and
//    pixels_per_texel 38.6 against the scene's 256x256 tactile map, and 4 colour views of 512x512
//    with their normal control images; the last one runs both, as the optimizer does per
//    refinement iteration.
// Every benchmark reports wall time (real time) and the CPU time of the whole process (all
// threads); on a shared machine the CPU time is the steadier number.
// Uses the real avocado tactile sample for the single-image benchmarks when ../shared/data is
// present ($TDF_SHARED_DATA or ../shared/data from the working folder), a synthetic exemplar
// otherwise.
#include <tdf/core/rng.h>
#include <tdf/core/vec.h>
#include <tdf/guidance/exemplar_patch_match.h>
#include <tdf/core/image_ops.h>
#include <tdf/guidance/relief_shading.h>
#include <tdf/tactile/tactile_map.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace tdf {
namespace {

Image exemplar() {
    const char* env = std::getenv("TDF_SHARED_DATA");
    const std::string path =
        std::string(env ? env : "../shared/data") + "/tactile/texture_samples/avocado_00000.png";
    if (std::filesystem::exists(path)) return load_tactile_map(path).normals;
    Image e(240, 240, 3);
    for (int y = 0; y < 240; ++y)
        for (int x = 0; x < 240; ++x) {
            const Vec3f n = safe_normalize(Vec3f(0.2f * float(x % 9 - 4), 0.2f * float(y % 7 - 3), 1.0f));
            e.at(x, y, 0) = n.x, e.at(x, y, 1) = n.y, e.at(x, y, 2) = n.z;
        }
    return e;
}

Image smooth_normals(int size) {
    Image n(size, size, 3);
    Rng rng(1);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const Vec3f v = safe_normalize(Vec3f(0.3f * rng.normal(), 0.3f * rng.normal(), 1.0f));
            n.at(x, y, 0) = v.x, n.at(x, y, 1) = v.y, n.at(x, y, 2) = v.z;
        }
    return gaussian_blur_masked(n, Image(), 3.0f);
}

void BM_ExemplarPatchMatch(benchmark::State& state) {
    const int size = int(state.range(0));
    ExemplarPatchMatchBackend backend({});
    backend.set_exemplars({exemplar()});
    GuidanceRequest request;
    request.kind = GuidanceKind::Tactile;
    request.strength = 0.8;
    request.images = {smooth_normals(size)};
    request.masks = {Image(size, size, 1, 1.0f)};
    for (auto _ : state) benchmark::DoNotOptimize(backend.refine(request));
    state.SetItemsProcessed(state.iterations() * size * size);
}
BENCHMARK(BM_ExemplarPatchMatch)
    ->Arg(128)
    ->Arg(256)
    ->Arg(512)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

void BM_ReliefShading(benchmark::State& state) {
    const int size = int(state.range(0));
    ReliefShadingBackend backend({});
    GuidanceRequest request;
    request.kind = GuidanceKind::Visual;
    request.strength = 0.5;
    request.images = {Image(size, size, 3, 0.6f)};
    request.control = {to_bae_control(smooth_normals(size))};
    request.masks = {Image(size, size, 1, 1.0f)};
    for (auto _ : state) benchmark::DoNotOptimize(backend.refine(request));
    state.SetItemsProcessed(state.iterations() * size * size);
}
BENCHMARK(BM_ReliefShading)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

// ---- One refinement iteration at the main job's sizes --------------------------------------

constexpr int kSize = 512;                // patch_resolution and resolution of the main job
constexpr int kImages = 4;                // patch_batch_size and batch_size
constexpr float kPixelsPerTexel = 38.6f;  // logged by `tdf optimize` on scenes/pebble_sphere

/// The main job's tactile map (scenes/pebble_sphere/tactile_normal.png, 256x256).
Image scene_tactile_map() {
    return load_tactile_map(std::string(TDF_SOURCE_DIR) + "/scenes/pebble_sphere/tactile_normal.png").normals;
}

/// Rodrigues rotation of v about the unit `axis` by `angle`.
Vec3f rotate_about(Vec3f v, Vec3f axis, float angle) {
    return v * std::cos(angle) + cross(axis, v) * std::sin(angle) +
           axis * (dot(axis, v) * (1.0f - std::cos(angle)));
}

/// Bilinear lookup of a tangent-space map at texel coordinates (wrapping, as a tiled map).
Vec3f sample_wrapped(const Image& map, float u, float v) {
    float n[3];
    sample_bilinear_texel(map, u, v, Addressing::Wrap, n);
    return safe_normalize(Vec3f(n[0], n[1], n[2]));
}

/// A tactile request like the optimizer's on the pebble sphere: each patch shows the map
/// magnified `kPixelsPerTexel` times, turned by a different angle (one chart mirrored), laid on
/// a sphere cap that tilts the surface by up to ~9 degrees across the window; the last patch
/// crosses the silhouette (30 % background, antialiased edge).
GuidanceRequest tactile_iteration_request(const Image& map) {
    GuidanceRequest r;
    r.kind = GuidanceKind::Tactile;
    r.strength = 0.8;
    r.seed = 11;
    r.iteration = 160;
    r.pixels_per_texel = kPixelsPerTexel;
    const float c = 0.5f * float(kSize - 1);
    for (int k = 0; k < kImages; ++k) {
        const float turn = 0.7f + 1.3f * float(k);
        const float handedness = k == 2 ? -1.0f : 1.0f;
        const float ct = std::cos(turn), st = std::sin(turn);
        Image normals(kSize, kSize, 3), mask(kSize, kSize, 1), base(kSize, kSize, 3),
            tangents(kSize, kSize, 4);
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const std::size_t p = std::size_t(y) * kSize + std::size_t(x);
                const float cover =
                    k == kImages - 1 ? std::clamp(0.7f * float(kSize) - float(x), 0.0f, 1.0f) : 1.0f;
                mask.data()[p] = cover;
                if (cover <= 0.0f) continue;  // background: zero vectors, as the renders have
                const Vec3f a =
                    safe_normalize(Vec3f((float(x) - c) / 1600.0f, (c - float(y)) / 1600.0f, 1.0f));
                const Vec3f axis = safe_normalize(cross(Vec3f(0, 0, 1), a));
                const float tilt = std::acos(std::clamp(a.z, -1.0f, 1.0f));
                // Texel coordinates of this pixel: the map turned by `turn`, mirrored on k == 2.
                const float u =
                    (ct * (float(x) - c) + st * (c - float(y))) / kPixelsPerTexel + 37.0f * float(k);
                const float v = handedness * (-st * (float(x) - c) + ct * (c - float(y))) / kPixelsPerTexel;
                Vec3f d = sample_wrapped(map, u, -v);
                d = Vec3f(ct * d.x - st * handedness * d.y, st * d.x + ct * handedness * d.y, d.z);
                const Vec3f n = tilt > 0.0f ? rotate_about(d, axis, tilt) : d;
                const Vec3f t = tilt > 0.0f ? rotate_about(Vec3f(ct, st, 0), axis, tilt) : Vec3f(ct, st, 0);
                std::copy(&n.x, &n.x + 3, normals.data() + 3 * p);
                std::copy(&a.x, &a.x + 3, base.data() + 3 * p);
                std::copy(&t.x, &t.x + 3, tangents.data() + 4 * p);
                tangents.data()[4 * p + 3] = handedness;
            }
        r.images.push_back(std::move(normals));
        r.masks.push_back(std::move(mask));
        r.surface_normals.push_back(std::move(base));
        r.surface_tangents.push_back(std::move(tangents));
    }
    return r;
}

/// A visual request like the optimizer's: 4 views of a sphere covering about half of each
/// 512x512 render, with the tactile relief (magnified as in the patches, smaller here) in the
/// normal control image and a coloured albedo, on white.
GuidanceRequest visual_iteration_request(const Image& map) {
    GuidanceRequest r;
    r.kind = GuidanceKind::Visual;
    r.strength = 0.56;
    r.seed = 11;
    r.iteration = 160;
    const float c = 0.5f * float(kSize - 1), radius = 0.4f * float(kSize);
    for (int k = 0; k < kImages; ++k) {
        Image colour(kSize, kSize, 3, 1.0f), normals(kSize, kSize, 3), mask(kSize, kSize, 1);
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const float px = (float(x) - c) / radius, py = (c - float(y)) / radius;
                const float rr = px * px + py * py;
                const float cover = std::clamp((1.0f - std::sqrt(rr)) * radius + 0.5f, 0.0f, 1.0f);
                const std::size_t p = std::size_t(y) * kSize + std::size_t(x);
                mask.data()[p] = cover;
                if (cover <= 0.0f) continue;
                const Vec3f a(px, py, std::sqrt(std::max(0.0f, 1.0f - rr)));
                const Vec3f d = sample_wrapped(map, float(x + 61 * k) / 6.0f, float(y) / 6.0f);
                const Vec3f n = safe_normalize(a + Vec3f(0.6f * d.x, 0.6f * d.y, 0.0f));
                std::copy(&n.x, &n.x + 3, normals.data() + 3 * p);
                const float shade = std::max(0.1f, dot(n, safe_normalize(Vec3f(0.3f, 0.4f, 1.0f))));
                const float albedo[3] = {
                    0.55f + 0.2f * std::sin(0.05f * float(x)), 0.45f, 0.35f + 0.1f * float(k)};
                for (int ch = 0; ch < 3; ++ch) {
                    const float lit = std::min(1.0f, albedo[ch] * shade);
                    colour.data()[3 * p + std::size_t(ch)] = cover * lit + (1.0f - cover);
                }
            }
        r.images.push_back(std::move(colour));
        r.control.push_back(to_bae_control(normals));
        r.masks.push_back(std::move(mask));
    }
    return r;
}

void BM_TactileRefinementIteration(benchmark::State& state) {
    const Image map = scene_tactile_map();
    auto backend = GuidanceBackend::create("exemplar_patch_match", Json::object());
    backend->set_exemplars({map});
    GuidanceRequest request = tactile_iteration_request(map);
    // Every refinement iteration has its own seed (as the trainer's); the cost does not depend on it.
    for (auto _ : state) {
        ++request.seed;
        benchmark::DoNotOptimize(backend->refine(request));
    }
    state.SetItemsProcessed(state.iterations() * kImages);
}
BENCHMARK(BM_TactileRefinementIteration)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

void BM_VisualRefinementIteration(benchmark::State& state) {
    auto backend = GuidanceBackend::create("relief_shading", Json::object());
    const GuidanceRequest request = visual_iteration_request(scene_tactile_map());
    for (auto _ : state) benchmark::DoNotOptimize(backend->refine(request));
    state.SetItemsProcessed(state.iterations() * kImages);
}
BENCHMARK(BM_VisualRefinementIteration)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

void BM_GuidancePerRefinementIteration(benchmark::State& state) {
    const Image map = scene_tactile_map();
    auto tactile = GuidanceBackend::create("exemplar_patch_match", Json::object());
    tactile->set_exemplars({map});
    auto visual = GuidanceBackend::create("relief_shading", Json::object());
    GuidanceRequest tactile_request = tactile_iteration_request(map);
    const GuidanceRequest visual_request = visual_iteration_request(map);
    for (auto _ : state) {
        ++tactile_request.seed;
        benchmark::DoNotOptimize(visual->refine(visual_request));
        benchmark::DoNotOptimize(tactile->refine(tactile_request));
    }
}
BENCHMARK(BM_GuidancePerRefinementIteration)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace
}  // namespace tdf

BENCHMARK_MAIN();
