// Rays (pixels) per second of a full multi-pass render at 512x512 against bare Embree closest-hit
// tracing of the same primary rays (the same packets and tiles: 16-wide where the CPU has
// AVX-512, 8-wide otherwise, chosen at run time). Scene: a 100k-triangle UV sphere with a 1024^2
// albedo and tactile map, seen from radius 2.5 (about 72% of the rays hit). The ray and raster
// producers and their full renders run on the same scene and camera in one run, plus the
// parts of the frame: the G-buffer alone (full frame, and in the renderer's tiles), and the two
// trilinear lookups per hit pixel alone.
// `bench/run.sh` prints every benchmark's ratio to BM_Baseline_EmbreePackets.
#include <benchmark/benchmark.h>
#include <tdf/core/parallel.h>
#include <tdf/render/raster.h>
#include <tdf/render/renderer.h>
#include <tdf/render/trace.h>
#include <tdf/scene/procedural_mesh.h>

#include <cmath>
#include <memory>

namespace {

using namespace tdf;

constexpr int kSize = 512;

struct BenchScene {
    TriangleMesh mesh = make_uv_sphere(1.f, 320, 160);  // 101,760 triangles
    EmbreeScene scene{mesh};
    MipTexture albedo;
    MipTexture tactile;
    Camera camera = Camera::orbit(-15, 30, 2.5f, 49.1f, kSize, kSize);

    BenchScene() {
        Image a(1024, 1024, 3), t(1024, 1024, 3);
        for (int y = 0; y < 1024; ++y)
            for (int x = 0; x < 1024; ++x) {
                const float s = std::sin(float(x) * 0.05f), c = std::cos(float(y) * 0.07f);
                a.at(x, y, 0) = 0.5f + 0.4f * s;
                a.at(x, y, 1) = 0.5f + 0.4f * c;
                a.at(x, y, 2) = 0.5f;
                const Vec3f n = safe_normalize({0.3f * s, 0.3f * c, 1.f});
                for (int k = 0; k < 3; ++k) t.at(x, y, k) = n[k];
            }
        albedo = MipTexture(a);
        tactile = MipTexture(t);
    }
    static const BenchScene& get() {
        static const BenchScene instance;
        return instance;
    }
};

void set_rays(benchmark::State& state) {
    state.counters["rays_per_s"] =
        benchmark::Counter(double(kSize) * kSize, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Baseline_EmbreePackets(benchmark::State& state) {
    const BenchScene& s = BenchScene::get();
    ThreadLimit limit(int(state.range(0)));
    std::vector<float> t;
    std::size_t hits = 0;
    for (auto _ : state) {
        hits = trace_closest_hits(s.scene, s.camera, t);
        benchmark::DoNotOptimize(t.data());
    }
    set_rays(state);
    state.counters["hit_fraction"] = double(hits) / (double(kSize) * kSize);
}

void BM_EmbreeSingleRays(benchmark::State& state) {
    const BenchScene& s = BenchScene::get();
    ThreadLimit limit(int(state.range(0)));
    std::vector<float> t(std::size_t(kSize) * kSize);
    for (auto _ : state) {
        parallel_for_tiles(
            kSize, kSize, kTraceTileWidth, kTraceTileHeight, [&](int x0, int y0, int x1, int y1) {
                for (int y = y0; y < y1; ++y)
                    for (int x = x0; x < x1; ++x)
                        t[std::size_t(y) * kSize + std::size_t(x)] =
                            trace_ray(s.scene, s.camera.generate_ray(float(x) + 0.5f, float(y) + 0.5f)).t;
            });
        benchmark::DoNotOptimize(t.data());
    }
    set_rays(state);
}

void gbuffer(benchmark::State& state, GBufferFields fields) {
    const BenchScene& s = BenchScene::get();
    ThreadLimit limit(int(state.range(0)));
    GBuffer g;
    for (auto _ : state) {
        trace_gbuffer(s.scene, s.mesh, s.camera, g, fields);
        benchmark::DoNotOptimize(g.mask.data());
    }
    set_rays(state);
}
// The full-frame G-buffer with every attribute (84 bytes a pixel: the evaluation, tests, tools).
void BM_GBuffer(benchmark::State& state) { gbuffer(state, GBufferFields::All); }
// The trainer's views: no triangle ids, barycentrics or depth (68 bytes a pixel).
void BM_GBufferShading(benchmark::State& state) { gbuffer(state, GBufferFields::Shading); }

// The renderer's G-buffer stage alone: every tile traced into the cache-resident lanes the
// renderer shades from (trace_tile_lanes), nothing written to full-frame arrays. The full-frame
// G-buffers above are these tiles written out (stream_gbuffer_tile), to eleven or eight arrays.
void BM_GBufferTiles(benchmark::State& state) {
    const BenchScene& s = BenchScene::get();
    ThreadLimit limit(int(state.range(0)));
    for (auto _ : state)
        parallel_for_tiles(
            kSize, kSize, kTraceTileWidth, kTraceTileHeight, [&](int x0, int y0, int x1, int y1) {
                static thread_local GBufferLanes lanes;  // per thread, as the renderer keeps it
                trace_tile_lanes(s.scene, s.mesh, s.camera, x0, y0, x1, y1, lanes);
                benchmark::DoNotOptimize(lanes.mask);
            });
    set_rays(state);
}

void BM_Raster_Visibility(benchmark::State& state) {
    const BenchScene& s = BenchScene::get();
    ThreadLimit limit(int(state.range(0)));
    RasterBuffer raster;
    for (auto _ : state) {
        rasterize(clip_positions(s.mesh, s.camera), s.mesh.triangles, kSize, kSize, raster);
        benchmark::DoNotOptimize(raster.rast.data());
    }
    set_rays(state);
}

void BM_Raster_GBuffer(benchmark::State& state) {
    const BenchScene& s = BenchScene::get();
    ThreadLimit limit(int(state.range(0)));
    GBuffer g;
    for (auto _ : state) {
        raster_gbuffer(s.mesh, s.camera, g);
        benchmark::DoNotOptimize(g.mask.data());
    }
    set_rays(state);
}

// The texture work alone: the albedo and tactile trilinear lookups of every hit pixel
// of a precomputed G-buffer (same tiles and threads as the renderer), nothing else.
void BM_Part_TwoTrilinearLookups(benchmark::State& state) {
    const BenchScene& s = BenchScene::get();
    ThreadLimit limit(int(state.range(0)));
    const GBuffer g = trace_gbuffer(s.scene, s.mesh, s.camera);
    std::vector<float> out(g.pixel_count() * 6);
    for (auto _ : state) {
        parallel_for_tiles(
            kSize, kSize, kTraceTileWidth, kTraceTileHeight, [&](int x0, int y0, int x1, int y1) {
                for (int y = y0; y < y1; ++y)
                    for (int x = x0; x < x1; ++x) {
                        const std::size_t i = g.index(x, y);
                        if (!(g.mask[i] > 0.f)) continue;
                        const float lod = s.albedo.level_of_detail(g.duv_dx[i], g.duv_dy[i]);
                        s.albedo.sample_trilinear_at(g.uv[i], lod, &out[6 * i]);
                        s.tactile.sample_trilinear_at(g.uv[i], lod, &out[6 * i + 3]);
                    }
            });
        benchmark::DoNotOptimize(out.data());
    }
    set_rays(state);
}

void render_passes(benchmark::State& state, ShadingMode mode, const std::vector<Pass>& passes,
                   bool textured = true, Visibility visibility = Visibility::Ray, bool antialias = false) {
    const BenchScene& s = BenchScene::get();
    ThreadLimit limit(int(state.range(0)));
    SurfaceMaterial material;
    if (textured) {
        material.albedo_source = SurfaceMaterial::AlbedoSource::Texture;
        material.albedo = &s.albedo;
        material.tactile = &s.tactile;
    }
    RenderSettings settings;
    settings.shading = mode;
    settings.visibility = visibility;
    settings.antialias = antialias;
    const Renderer renderer(s.mesh, s.scene, material, settings);
    const Light light{Light::Kind::Point, {2, 3, 4}, 0.5f};
    Frame frame;  // reused: steady-state cost without allocating the output images
    for (auto _ : state) {
        renderer.render(s.camera, light, passes, frame);
        benchmark::DoNotOptimize(frame.images.data());
    }
    set_rays(state);
}

const std::vector<Pass> kTenPasses = {Pass::Albedo,
                                      Pass::Lambertian,
                                      Pass::Mask,
                                      Pass::Depth,
                                      Pass::Normal,
                                      Pass::Tangent,
                                      Pass::Uv,
                                      Pass::TactileNormal,
                                      Pass::ShadingNormal,
                                      Pass::ShadingNormalViewspace};

// Every pass but label (no label map here): the "full multi-pass render".
void BM_Render_Training(benchmark::State& state) { render_passes(state, ShadingMode::Training, kTenPasses); }
void BM_Render_Visualizer(benchmark::State& state) {
    render_passes(state, ShadingMode::Visualizer, kTenPasses);
}
// Only the shaded image and coverage (still both texture lookups and the TBN frame).
void BM_Render_LambertianOnly(benchmark::State& state) {
    render_passes(state, ShadingMode::Training, {Pass::Lambertian, Pass::Mask});
}

#define TDF_RENDER_BENCH(fn) \
    BENCHMARK(fn)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()
TDF_RENDER_BENCH(BM_Baseline_EmbreePackets);
TDF_RENDER_BENCH(BM_EmbreeSingleRays);
TDF_RENDER_BENCH(BM_GBuffer);
TDF_RENDER_BENCH(BM_GBufferShading);
TDF_RENDER_BENCH(BM_GBufferTiles);
TDF_RENDER_BENCH(BM_Raster_Visibility);
TDF_RENDER_BENCH(BM_Raster_GBuffer);
TDF_RENDER_BENCH(BM_Part_TwoTrilinearLookups);
TDF_RENDER_BENCH(BM_Render_Training);
TDF_RENDER_BENCH(BM_Render_Visualizer);
TDF_RENDER_BENCH(BM_Render_LambertianOnly);
// The same without textures (constant albedo, flat tactile normal): the cost of the lookups.
void BM_Render_LambertianUntextured(benchmark::State& state) {
    render_passes(state, ShadingMode::Training, {Pass::Lambertian, Pass::Mask}, false);
}
TDF_RENDER_BENCH(BM_Render_LambertianUntextured);
// The same 10-pass training render with the raster producer, without and with dr.antialias, and
// the ray producer with dr.antialias.
void BM_Render_Training_Raster(benchmark::State& state) {
    render_passes(state, ShadingMode::Training, kTenPasses, true, Visibility::Raster, false);
}
void BM_Render_Training_RasterAA(benchmark::State& state) {
    render_passes(state, ShadingMode::Training, kTenPasses, true, Visibility::Raster, true);
}
void BM_Render_Training_RayAA(benchmark::State& state) {
    render_passes(state, ShadingMode::Training, kTenPasses, true, Visibility::Ray, true);
}
TDF_RENDER_BENCH(BM_Render_Training_Raster);
TDF_RENDER_BENCH(BM_Render_Training_RasterAA);
TDF_RENDER_BENCH(BM_Render_Training_RayAA);

}  // namespace

BENCHMARK_MAIN();
