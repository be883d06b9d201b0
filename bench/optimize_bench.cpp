// The texture-space optimizer of `tdf optimize` on the shipped scene scenes/pebble_sphere with
// the defaults of its scene.json (texture schedule, default guidance backends):
//  - BM_MatchingIteration, BM_RefinementIteration: seconds per iteration by stage (counters
//    s_<stage>, from Trainer::stage_times()) and the process's peak RSS so far (peak_RSS_MB).
//    Refinement starts from a checkpoint of the matching iterations before it (Trainer::restore
//    at iteration init_iterations), so a few iterations of each phase are enough.
//  - BM_FieldForwardBackward/<points> against BM_BaselineGatherScatter/<points>: the field's
//    forward + backward (cached encodings, the trainer's path) on the atlas's texel points,
//    against a floor that reads and writes exactly the same hash-table entries (same indices
//    from HashGrid::corners, same level-by-level order, trilinear weights, no hashing and no
//    heads). 65536 points = a matching iteration's random texel sample; all covered texels =
//    one full evaluation of the maps (LearnedMaps::evaluate_field). One thread each: the ratio
//    says how far one core of the field is from the memory floor.
// Run: cmake --build build --target tdf_optimize_bench && bench/run.sh optimize
// (BENCH_ARGS="--benchmark_repetitions=3" for medians.)
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/field/texture_field.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/render/scene_assets.h>
#include <tdf/scene/scene_file.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/train/run_config.h>
#include <tdf/train/trainer.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace tdf;

const Json& section(const SceneDescription& d, const char* name) {
    static const Json kNull;
    const auto it = d.sections.find(name);
    return it == d.sections.end() ? kNull : it->second;
}

// The main job's setup, as run_optimize builds it (src/train/optimize_run.cpp), built once.
struct Job {
    SceneDescription description;
    RunConfig config;
    std::unique_ptr<SceneAssets> assets;
    TrainingTarget target;
    std::unique_ptr<Trainer> trainer;

    Job() {
        const std::string path = std::string(TDF_SOURCE_DIR) + "/scenes/pebble_sphere/scene.json";
        description = load_scene(path);
        config = RunConfig::from_json(section(description, "optimize"),
                                      section(description, "tactile_layout"),
                                      section(description, "export"),
                                      section(description, "guidance"),
                                      path,
                                      section(description, "field"),
                                      section(description, "schedule"));
        assets = load_scene_assets(description);
        target.mesh = &assets->mesh;
        target.scene = assets->scene.get();
        target.material = &assets->material;
        target.prompt = "pebble sphere";  // the prompt only reaches external backends
        trainer = std::make_unique<Trainer>(target, config, description.seed);
        trainer->set_guidance(backend(config.guidance_visual), backend(config.guidance_tactile));
    }

    std::unique_ptr<GuidanceBackend> backend(const std::string& name) const {
        const Json cfg =
            config.guidance_config.contains(name) ? config.guidance_config[name] : Json::object();
        auto b = GuidanceBackend::create(name, cfg);
        if (b && !cfg.contains("exemplars")) {
            std::vector<Image> exemplars;
            for (const std::string& p : description.tactile_images)
                exemplars.push_back(load_tactile_map(p).normals);
            b->set_exemplars(std::move(exemplars));
        }
        return b;
    }
};

Job& job() {
    static Job j;
    return j;
}

double thread_cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

double peak_rss_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0;  // kilobytes on Linux
}

void stage_counters(benchmark::State& state, const StageTimes& before, const StageTimes& after) {
    const double n = double(state.iterations());
    const auto per = [&](double a, double b) { return benchmark::Counter((b - a) / n); };
    state.counters["s_matching"] = per(before.matching, after.matching);
    state.counters["s_tracing"] = per(before.tracing, after.tracing);
    state.counters["s_lookups"] = per(before.field_forward, after.field_forward);
    state.counters["s_losses"] = per(before.losses, after.losses);
    state.counters["s_guidance"] = per(before.guidance, after.guidance);
    state.counters["s_backward"] = per(before.field_backward, after.field_backward);
    state.counters["s_update"] = per(before.adam, after.adam);
    state.counters["threads"] = ThreadLimit::current();
    state.counters["peak_RSS_MB"] = peak_rss_mb();
}

// Matching iterations from iteration 0 (no rendering: a random texel sample fitted to the targets).
void BM_MatchingIteration(benchmark::State& state) {
    Trainer& trainer = *job().trainer;
    const int matching = job().config.init_iterations;
    trainer.restore(0, trainer.parameters(), trainer.optimizer_state());
    const StageTimes before = trainer.stage_times();
    for (auto _ : state) {
        if (trainer.iteration() >= matching) state.SkipWithError("past the matching phase");
        benchmark::DoNotOptimize(trainer.step());
    }
    stage_counters(state, before, trainer.stage_times());
}

// Refinement iterations from the start of the phase, after one untimed warm-up iteration (the
// guidance backends' first call builds their caches).
void BM_RefinementIteration(benchmark::State& state) {
    Trainer& trainer = *job().trainer;
    trainer.restore(job().config.init_iterations, trainer.parameters(), trainer.optimizer_state());
    trainer.step();
    const StageTimes before = trainer.stage_times();
    for (auto _ : state) {
        if (trainer.iteration() >= job().config.iterations) state.SkipWithError("past the last iteration");
        benchmark::DoNotOptimize(trainer.step());
    }
    stage_counters(state, before, trainer.stage_times());
}

// ---- The field against its memory floor ---------------------------------------------------

// The texel points: the first `n` of a random sample of covered texels (as a matching iteration
// draws them), or all covered texels in atlas order (n = 0).
std::vector<Vec3f> texel_points(std::size_t n) {
    const TexelAtlas& atlas = *job().trainer->texel_atlas();
    if (n == 0) return atlas.points;
    std::vector<Vec3f> p(n);
    Rng rng(7);
    for (Vec3f& x : p) x = atlas.points[std::size_t(rng.uniform_int(0, int(atlas.covered_count()) - 1))];
    return p;
}

// The trainer's field path: forward keeping the encodings, backward from them.
void BM_FieldForwardBackward(benchmark::State& state) {
    ThreadLimit limit(1);
    const TextureField& field = job().trainer->field();
    const std::vector<Vec3f> points = texel_points(std::size_t(state.range(0)));
    const std::size_t n = points.size();
    std::vector<FieldOutputs> out(n);
    std::vector<FieldOutputGrads> grads(n);
    Rng rng(2);
    for (FieldOutputGrads& g : grads) {
        g.d_albedo = {rng.uniform(-1, 1) * 1e-6f, rng.uniform(-1, 1) * 1e-6f, rng.uniform(-1, 1) * 1e-6f};
        g.d_normal = {rng.uniform(-1, 1) * 1e-6f, rng.uniform(-1, 1) * 1e-6f, rng.uniform(-1, 1) * 1e-6f};
    }
    std::vector<float> gradient(field.parameter_count());
    FieldCache cache;
    field.evaluate(points.data(), n, out.data(), cache);  // steady state: the cache has its memory
    for (auto _ : state) {
        field.evaluate(points.data(), n, out.data(), cache);
        std::fill(gradient.begin(), gradient.end(), 0.0f);
        field.backward(points.data(), grads.data(), n, gradient, cache);
        benchmark::DoNotOptimize(gradient.data());
    }
    state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(n));
    state.counters["points"] = double(n);
}

// The floor: the same table entries gathered (forward) and scattered (backward), nothing else.
// Corners are computed untimed per block of points (manual time: the reported real time is the
// gather + scatter only; the CPU time includes the corners), so the timed part is the memory
// traffic: per level, 8 weighted reads of 2 floats per point, then 8 weighted read-modify-writes
// of 2 floats per point into the gradient.
void BM_BaselineGatherScatter(benchmark::State& state) {
    ThreadLimit limit(1);
    const TextureField& field = job().trainer->field();
    const HashGrid& grid = field.grid();
    const std::vector<Vec3f> points = texel_points(std::size_t(state.range(0)));
    const std::size_t n = points.size(), levels = std::size_t(grid.level_count());
    constexpr std::size_t kBlock = 2048;                // TextureField's encode block
    std::vector<GridCorners> corners(levels * kBlock);  // level-major
    std::vector<float> features(levels * 2 * kBlock);
    const float* table = field.parameters().data() + field.parameter_block("grid").offset;
    std::vector<float> gradient(field.parameter_count());
    using Clock = std::chrono::steady_clock;
    double cpu_seconds = 0;
    for (auto _ : state) {
        std::fill(gradient.begin(), gradient.end(), 0.0f);
        double seconds = 0;
        for (std::size_t b = 0; b < n; b += kBlock) {
            const std::size_t count = std::min(kBlock, n - b);
            for (std::size_t l = 0; l < levels; ++l)
                for (std::size_t i = 0; i < count; ++i)
                    grid.corners(int(l), field.to_grid(points[b + i]), corners[l * kBlock + i]);
            const auto t0 = Clock::now();
            const double cpu0 = thread_cpu_seconds();
            for (std::size_t l = 0; l < levels; ++l) {
                const float* level_table = table + std::size_t(grid.levels()[l].offset) * 2;
                float* f = features.data() + l * 2 * kBlock;
                // The field's gather prefetches the even corners of hashed levels (hash_grid.cpp);
                // the floor does the same, so it stays below the field.
                if (grid.levels()[l].hashed)
                    for (std::size_t i = 0; i < count; ++i)
                        for (int k = 0; k < 8; k += 2)
                            __builtin_prefetch(level_table +
                                               std::size_t(corners[l * kBlock + i].index[k]) * 2);
                for (std::size_t i = 0; i < count; ++i) {
                    const GridCorners& c = corners[l * kBlock + i];
                    float a = 0, d = 0;
                    for (int k = 0; k < 8; ++k) {
                        const float* e = level_table + std::size_t(c.index[k]) * 2;
                        a += c.weight[k] * e[0];
                        d += c.weight[k] * e[1];
                    }
                    f[i] = a;
                    f[kBlock + i] = d;
                }
            }
            for (std::size_t l = 0; l < levels; ++l) {
                float* level_gradient = gradient.data() + std::size_t(grid.levels()[l].offset) * 2;
                const float* f = features.data() + l * 2 * kBlock;
                for (std::size_t i = 0; i < count; ++i) {
                    const GridCorners& c = corners[l * kBlock + i];
                    for (int k = 0; k < 8; ++k) {
                        float* e = level_gradient + std::size_t(c.index[k]) * 2;
                        e[0] += c.weight[k] * f[i];
                        e[1] += c.weight[k] * f[kBlock + i];
                    }
                }
            }
            seconds += std::chrono::duration<double>(Clock::now() - t0).count();
            cpu_seconds += thread_cpu_seconds() - cpu0;
        }
        benchmark::DoNotOptimize(gradient.data());
        state.SetIterationTime(seconds);
    }
    state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(n));
    state.counters["points"] = double(n);
    // CPU milliseconds of the gather + scatter alone (the steadiest number on a shared machine;
    // compare with the field's cpu ms).
    state.counters["cpu_ms_floor"] = cpu_seconds * 1e3 / double(state.iterations());
}

}  // namespace

// Fixed, small iteration counts: one matching iteration takes about a second, a refinement
// iteration several (shared 2-core machine; see README "tdf optimize").
// CPU time of the trainer benchmarks is the whole process's (all worker threads).
BENCHMARK(BM_MatchingIteration)
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();
BENCHMARK(BM_RefinementIteration)
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();
BENCHMARK(BM_BaselineGatherScatter)->Arg(1 << 16)->Arg(0)->Unit(benchmark::kMillisecond)->UseManualTime();
BENCHMARK(BM_FieldForwardBackward)->Arg(1 << 16)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();
