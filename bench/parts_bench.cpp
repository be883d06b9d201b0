// Multi-part segmentation and target composition timing at the optimizer's default 1024^2
// texture. From the repository root (it reads scenes/ and, for spot, ../shared/data):
//   ./build/bench/tdf_parts_bench --benchmark_repetitions=3
// segment/<scene>/<source>: segment_parts alone (the mesh and albedo are loaded once, outside
// the timing). compose/<n>_parts: laying n tactile maps over the atlas and composing the target
// over a two_part_sphere segmentation relabelled into n bands (the composition cost of parts).
// CPU time of the process is reported (the machine is shared); wall time is noisy.
#include <tdf/core/error.h>
#include <tdf/parts/part_segmentation.h>
#include <tdf/parts/part_target.h>
#include <tdf/render/scene_assets.h>
#include <tdf/tactile/tactile_map.h>

#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <memory>

namespace {

using namespace tdf;

constexpr int kSize = 1024;

struct Loaded {
    SceneDescription description;
    std::unique_ptr<SceneAssets> assets;
};

std::shared_ptr<Loaded> load(const std::string& scene) {
    auto l = std::make_shared<Loaded>();
    l->description = load_scene(scene);
    l->assets = load_scene_assets(l->description);
    return l;
}

PartSegmentationInput input_of(const Loaded& l) {
    PartSegmentationInput in;
    in.mesh = in.atlas = &l.assets->mesh;
    in.material = &l.assets->material;
    in.size = kSize;
    in.where = l.description.path;
    return in;
}

void register_segment(const std::string& name, const std::shared_ptr<Loaded>& l, PartsSpec spec) {
    benchmark::RegisterBenchmark(name.c_str(),
                                 [l, spec](benchmark::State& state) {
                                     for (auto _ : state) benchmark::DoNotOptimize(segment_parts(spec, input_of(*l)));
                                 })
        ->Unit(benchmark::kMillisecond)
        ->MeasureProcessCPUTime()
        ->Iterations(1);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const std::string two = "scenes/two_part_sphere";
        if (!std::filesystem::exists(two + "/scene.json")) {
            std::fprintf(stderr, "parts bench: run it from the repository root\n");
            return 1;
        }
        const auto sphere = load(two + "/scene.json");
        PartsSpec colour = sphere->description.parts;
        register_segment("segment/two_part_sphere/colour", sphere, colour);
        PartsSpec mesh = colour;
        mesh.source.kind = "mesh";
        mesh.parts[0].select = {"cap"};
        register_segment("segment/two_part_sphere/mesh", sphere, mesh);
        PartsSpec faces = mesh;
        faces.source.kind = "face_labels";
        faces.source.file = two + "/labels.txt";
        register_segment("segment/two_part_sphere/face_labels", sphere, faces);
        PartsSpec image = mesh;
        image.source.kind = "label_image";
        image.source.image = two + "/label_image.png";
        image.parts[0].select = {"#ff0000"};
        register_segment("segment/two_part_sphere/label_image", sphere, image);
        if (std::filesystem::exists("../shared/data/meshes/spot/spot_triangulated.obj")) {
            const auto spot = load("scenes/spot_parts/scene.json");
            register_segment("segment/spot_parts/colour", spot, spot->description.parts);
        } else {
            std::fprintf(stderr, "parts bench: no ../shared/data; skipping spot\n");
        }

        // Composition with 1, 2 and 4 parts: the sphere's texels relabelled by height bands.
        const PartSegmentation seg = segment_parts(mesh, input_of(*sphere));
        auto maps = std::make_shared<std::vector<MipTexture>>();
        for (const char* file : {"ribs_normal.png", "../pebble_sphere/tactile_normal.png"})
            maps->emplace_back(load_tactile_map(two + "/" + file).normals);
        for (int n : {1, 2, 4}) {
            std::vector<int> labels = seg.texel_part;
            for (std::size_t i = 0; i < labels.size(); ++i)
                if (labels[i] >= 0) labels[i] = int((i / std::size_t(kSize)) * std::size_t(n) / std::size_t(kSize));
            std::vector<PartTactile> tactile;
            for (int p = 0; p < n; ++p) tactile.push_back({&(*maps)[std::size_t(p % 2)], float(1 + p)});
            benchmark::RegisterBenchmark(("compose/" + std::to_string(n) + "_parts").c_str(),
                                         [maps, labels, tactile](benchmark::State& state) {
                                             for (auto _ : state) {
                                                 const std::vector<Image> layers = lay_part_maps(tactile, kSize);
                                                 benchmark::DoNotOptimize(compose_part_target(labels, kSize, layers));
                                             }
                                         })
                ->Unit(benchmark::kMillisecond)
                ->MeasureProcessCPUTime()
                ->Iterations(1);
        }
    } catch (const Error& e) {
        std::fprintf(stderr, "parts bench: %s\n", e.what());
        return 1;
    }
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
