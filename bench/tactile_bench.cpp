// Quilting throughput: a 256x256 exemplar to a 1024x1024 map with 40-pixel blocks (the README's
// "Measured" numbers), and the whole `tdf tactile convert` pipeline (patch, quilt, normals,
// material statistics) on a 240^2 sample and a 2048^2 height map.
// Run: ./build/tdf_tactile_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/pipeline.h>
#include <tdf/tactile/quilting.h>

#include <algorithm>

#include <cmath>

namespace {

// A deterministic stand-in for a height patch: random waves at several scales.
tdf::Image exemplar(int size) {
    tdf::Rng rng(2024);
    tdf::Image image(size, size, 1);
    for (int wave = 0; wave < 16; ++wave) {
        const float angle = rng.uniform(0.0f, 6.2831853f), frequency = rng.uniform(0.03f, 0.5f);
        const float phase = rng.uniform(0.0f, 6.2831853f), amplitude = rng.uniform(0.1f, 1.0f);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                image.at(x, y, 0) +=
                    amplitude *
                    std::sin(frequency * (std::cos(angle) * float(x) + std::sin(angle) * float(y)) + phase);
    }
    return image;
}

void quilt_256_to_1024(benchmark::State& state) {
    const tdf::Image patch = exemplar(256);
    tdf::QuiltOptions options;
    options.size = 1024;
    options.block = 40;
    options.tileable = state.range(1) != 0;
    tdf::ThreadLimit limit(int(state.range(0)));
    std::uint64_t candidates = 0;
    for (auto _ : state) {
        const tdf::QuiltResult result = tdf::quilt({patch}, options);
        candidates += result.stats.candidates;
        benchmark::DoNotOptimize(result.image.data());
    }
    state.counters["candidates/s"] = benchmark::Counter(double(candidates), benchmark::Counter::kIsRate);
}

// `tdf tactile convert` with its defaults on a height image of `side` pixels (no sensor
// metadata): textured region, patch at full resolution, tileable 1020 px quilt (block auto),
// normals, and the statistics it reports.
void convert_pipeline(benchmark::State& state) {
    const int side = int(state.range(0));
    tdf::HeightInput input;
    input.map.height = exemplar(side);
    for (float& v : input.map.height.values()) v *= 0.02f;
    input.map.source = "synthetic";
    input.kind = "height image";
    tdf::QuiltOptions options;
    options.size = 1024;
    options.tileable = true, options.min_contrast = 0.9f, options.feather = 2;
    options.block = std::max(40, side / 8 / 8 * 8);
    for (auto _ : state) {
        tdf::PatchSteps steps;
        const tdf::HeightMap patch = tdf::extract_patch(input, tdf::PatchOptions{}, &steps);
        const tdf::HeightMap quilted = tdf::quilt_height_maps({patch}, options);
        const float strength = tdf::auto_strength(patch, tdf::Amplitude::Auto);
        const tdf::Image normals = tdf::quantized_normals(
            tdf::normal_map_from_height(quilted, tdf::Amplitude::Auto, strength), 8);
        const tdf::MaterialComparison c =
            tdf::compare_material(tdf::scale_normal_slopes(steps.input_normals, strength), steps.region, normals);
        state.counters["tilt_ratio"] = c.tilt_ratio;
        benchmark::DoNotOptimize(normals.data());
    }
}

}  // namespace

BENCHMARK(convert_pipeline)->Arg(240)->Arg(2048)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// Arguments: threads (0 = all), tileable.
BENCHMARK(quilt_256_to_1024)
    ->Args({1, 0})
    ->Args({0, 0})
    ->Args({0, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
