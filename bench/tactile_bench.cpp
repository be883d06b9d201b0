// Quilting throughput: a 256x256 exemplar to a 1024x1024 map with 40-pixel blocks (the README's
// "Measured" numbers). Run: ./build/tdf_tactile_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/tactile/quilting.h>

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

}  // namespace

// Arguments: threads (0 = all), tileable.
BENCHMARK(quilt_256_to_1024)
    ->Args({1, 0})
    ->Args({0, 0})
    ->Args({0, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
