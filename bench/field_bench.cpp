// Texture field throughput for one default iteration's worth of points (issue 5 target:
// forward + backward + Adam for 2.6 million points in about 0.22 s on 2 threads).
//
// The points are surface points of a unit sphere seen from 10 orthographic 512x512 views
// (raster order, background skipped), so the memory access pattern is as coherent as a real
// render's. Run: build/bench/tdf_field_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/field/texture_field.h>
#include <tdf/optim/adam.h>

#include <cmath>
#include <vector>

namespace {

using namespace tdf;

constexpr std::size_t kPoints = 10 * 512 * 512;  // ~2.6 M: one default iteration

const std::vector<Vec3f>& sphere_points() {
    static const std::vector<Vec3f> points = [] {
        std::vector<Vec3f> p;
        p.reserve(kPoints);
        Rng rng(1);
        while (p.size() < kPoints) {
            // A random orthographic view direction with a tangent frame.
            const float z = rng.uniform(-1, 1), phi = rng.uniform(0, 2 * kPi);
            const Vec3f d(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
            const Vec3f t = safe_normalize(cross(d, std::abs(d.y) < 0.9f ? Vec3f(0, 1, 0) : Vec3f(1, 0, 0)));
            const Vec3f b = cross(d, t);
            for (int y = 0; y < 512 && p.size() < kPoints; ++y)
                for (int x = 0; x < 512 && p.size() < kPoints; ++x) {
                    const float u = (float(x) + 0.5f) / 256.0f - 1.0f, v = (float(y) + 0.5f) / 256.0f - 1.0f;
                    const float r2 = u * u + v * v;
                    if (r2 >= 1.0f) continue;  // background: the trainer passes no such points
                    p.push_back(t * u + b * v + d * std::sqrt(1.0f - r2));
                }
        }
        return p;
    }();
    return points;
}

const FieldDomain kDomain{{-1, -1, -1}, {1, 1, 1}};

std::vector<FieldOutputGrads> upstream_gradients() {
    std::vector<FieldOutputGrads> g(kPoints);
    Rng rng(2);
    for (FieldOutputGrads& x : g) {
        x.d_albedo = {rng.uniform(-1, 1) * 1e-6f, rng.uniform(-1, 1) * 1e-6f, rng.uniform(-1, 1) * 1e-6f};
        x.d_normal = {rng.uniform(-1, 1) * 1e-6f, rng.uniform(-1, 1) * 1e-6f, rng.uniform(-1, 1) * 1e-6f};
    }
    return g;
}

void report(benchmark::State& state) {
    state.counters["Mpoints/s"] =
        benchmark::Counter(double(kPoints) * double(state.iterations()) * 1e-6, benchmark::Counter::kIsRate);
}

void BM_FieldForward(benchmark::State& state) {
    ThreadLimit limit(int(state.range(0)));
    const TextureField field(FieldConfig{}, kDomain, 1);
    const auto& points = sphere_points();
    std::vector<FieldOutputs> out(kPoints);
    for (auto _ : state) {
        field.evaluate(points.data(), kPoints, out.data());
        benchmark::DoNotOptimize(out.data());
    }
    report(state);
}

void BM_FieldBackward(benchmark::State& state) {
    ThreadLimit limit(int(state.range(0)));
    const TextureField field(FieldConfig{}, kDomain, 1);
    const auto& points = sphere_points();
    const auto grads = upstream_gradients();
    std::vector<float> gradient(field.parameter_count());
    for (auto _ : state) {
        std::fill(gradient.begin(), gradient.end(), 0.0f);
        field.backward(points.data(), grads.data(), kPoints, gradient);
        benchmark::DoNotOptimize(gradient.data());
    }
    report(state);
}

// Backward reading the encodings that a cached evaluate() kept (the trainer's path).
void BM_FieldBackwardCached(benchmark::State& state) {
    ThreadLimit limit(int(state.range(0)));
    const TextureField field(FieldConfig{}, kDomain, 1);
    const auto& points = sphere_points();
    const auto grads = upstream_gradients();
    std::vector<FieldOutputs> out(kPoints);
    FieldCache cache;
    field.evaluate(points.data(), kPoints, out.data(), cache);
    std::vector<float> gradient(field.parameter_count());
    for (auto _ : state) {
        std::fill(gradient.begin(), gradient.end(), 0.0f);
        field.backward(points.data(), grads.data(), kPoints, gradient, cache);
        benchmark::DoNotOptimize(gradient.data());
    }
    report(state);
}

void BM_Adam(benchmark::State& state) {
    ThreadLimit limit(int(state.range(0)));
    TextureField field(FieldConfig{}, kDomain, 1);
    Adam adam(field.parameter_count());
    const std::vector<float> gradient(field.parameter_count(), 1e-3f);
    for (auto _ : state) adam.step(field.parameters(), gradient);
    state.counters["params"] = double(field.parameter_count());
}

// One training iteration of the field as the trainer runs it: forward for the losses (keeping
// the encodings), backward from the cache, Adam.
void BM_FieldIteration(benchmark::State& state) {
    ThreadLimit limit(int(state.range(0)));
    TextureField field(FieldConfig{}, kDomain, 1);
    Adam adam(field.parameter_count());
    const auto& points = sphere_points();
    const auto grads = upstream_gradients();
    std::vector<FieldOutputs> out(kPoints);
    std::vector<float> gradient(field.parameter_count());
    FieldCache cache;
    // Steady state: the trainer's cache has its memory after the first iteration.
    field.evaluate(points.data(), kPoints, out.data(), cache);
    for (auto _ : state) {
        field.evaluate(points.data(), kPoints, out.data(), cache);
        std::fill(gradient.begin(), gradient.end(), 0.0f);
        field.backward(points.data(), grads.data(), kPoints, gradient, cache);
        adam.step(field.parameters(), gradient);
    }
    report(state);
}

}  // namespace

BENCHMARK(BM_FieldForward)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FieldBackward)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FieldBackwardCached)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Adam)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FieldIteration)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();
