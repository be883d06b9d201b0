// Cost of the built-in guidance backends per image (the reference refines 4 patches and 1-4
// views per iteration, spec 5.4-5.5). Uses the real avocado tactile sample when ../shared/data
// is present ($TDF_SHARED_DATA or ../shared/data from the working folder), a synthetic exemplar
// otherwise.
#include <tdf/core/rng.h>
#include <tdf/core/vec.h>
#include <tdf/guidance/exemplar_patch_match.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/guidance/image_filters.h>
#include <tdf/guidance/relief_shading.h>

#include <benchmark/benchmark.h>

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
BENCHMARK(BM_ExemplarPatchMatch)->Arg(128)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond);

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
BENCHMARK(BM_ReliefShading)->Arg(512)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tdf

BENCHMARK_MAIN();
