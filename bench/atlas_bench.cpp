// UV atlas timing and quality on the shared meshes (spot, mug, avocado when its loader is
// there) and on spot subdivided to ~94k triangles. From the repository root (it reads
// ../shared/data): ./build/bench/tdf_atlas_bench
// Counters: utilisation (fraction of the 1024^2 texels covered), charts, mean L2 stretch,
// overlaps. Timings are wall time on a shared machine: expect noise.
#include <benchmark/benchmark.h>
#include <tdf/atlas/uv_atlas.h>
#include <tdf/core/error.h>
#include <tdf/mesh/mesh_io.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <utility>

namespace {

using namespace tdf;

// Splits every triangle into four at its edge midpoints (shared between neighbours).
TriangleMesh subdivide(const TriangleMesh& mesh) {
    TriangleMesh out;
    out.positions = mesh.positions;
    std::map<std::pair<int, int>, int> midpoint;
    const auto mid = [&](int a, int b) {
        const auto key = std::make_pair(std::min(a, b), std::max(a, b));
        const auto [it, inserted] = midpoint.emplace(key, int(out.positions.size()));
        if (inserted)
            out.positions.push_back((mesh.positions[std::size_t(a)] + mesh.positions[std::size_t(b)]) * 0.5f);
        return it->second;
    };
    for (const Vec3i& t : mesh.triangles) {
        const int ab = mid(t.x, t.y), bc = mid(t.y, t.z), ca = mid(t.z, t.x);
        out.triangles.push_back({t.x, ab, ca});
        out.triangles.push_back({ab, t.y, bc});
        out.triangles.push_back({ca, bc, t.z});
        out.triangles.push_back({ab, bc, ca});
    }
    finish_loaded_mesh(out, "subdivided", {});
    return out;
}

void run_atlas(benchmark::State& state, const TriangleMesh& mesh) {
    AtlasOptions options;
    options.reunwrap = true;
    AtlasReport report;
    for (auto _ : state) benchmark::DoNotOptimize(build_atlas(mesh, options, &report));
    state.counters["faces"] = double(report.faces);
    state.counters["charts"] = double(report.chart_count);
    state.counters["utilisation"] = report.utilisation;
    state.counters["stretch"] = report.stretch_mean;
    state.counters["overlaps"] = double(report.overlaps);
}

// $TDF_SHARED_DATA, else ../shared/data from the working folder (run from the repository root).
std::string shared_data_dir() {
    if (const char* env = std::getenv("TDF_SHARED_DATA")) return env;
    return std::filesystem::is_directory("../shared/data") ? "../shared/data" : "";
}

void register_mesh(const std::string& name, const std::string& relative, int subdivisions = 0) {
    const std::string root = shared_data_dir();
    if (root.empty()) {
        std::fprintf(
            stderr, "atlas bench: no ../shared/data (or $TDF_SHARED_DATA); skipping %s\n", name.c_str());
        return;
    }
    try {
        MeshLoadOptions options;
        options.load_textures = false;
        TriangleMesh mesh = load_mesh(root + "/" + relative, options);
        for (int i = 0; i < subdivisions; ++i) mesh = subdivide(mesh);
        benchmark::RegisterBenchmark(name.c_str(),
                                     [mesh](benchmark::State& state) { run_atlas(state, mesh); })
            ->Unit(benchmark::kMillisecond)
            ->Iterations(1);
    } catch (const Error& e) {
        std::fprintf(stderr, "atlas bench: skipping %s: %s\n", name.c_str(), e.what());
    }
}

}  // namespace

int main(int argc, char** argv) {
    register_mesh("atlas/spot", "meshes/spot/spot_triangulated.obj");
    register_mesh("atlas/avocado", "meshes/avocado_gltf/Avocado.gltf");
    register_mesh("atlas/mug", "meshes/mug/mug.obj");
    register_mesh("atlas/spot_x16", "meshes/spot/spot_triangulated.obj", 2);
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
