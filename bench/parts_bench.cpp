// Multi-part segmentation and target composition timing at the optimizer's default 1024^2
// texture. From the repository root (it reads scenes/ and, for spot, ../shared/data):
//   ./build/bench/tdf_parts_bench --benchmark_repetitions=3
// segment/<scene>/<source>: segment_parts alone (the mesh and albedo are loaded once, outside
// the timing). compose/<n>_parts: laying n tactile maps over the atlas and composing the target
// over a two_part_sphere segmentation relabelled into n bands (the composition cost of parts).
// refine/<n>_parts: one refinement iteration of the texture-space optimizer on two_part_sphere at
// 512^2 (`tdf optimize` defaults otherwise: cameras, visual relief_shading guidance, tactile
// exemplar_patch_match guidance) with 1 part (the scene without `parts`), the scene's 2 parts,
// and 4 and 8 parts (bands, tests/common/four_part_sphere.h); each part has its own tactile backend with its
// own map as exemplar, gated by its mask. The 20 matching iterations and one refinement
// iteration run before the timing.
// CPU time of the process is reported (the machine is shared); wall time is noisy.
#include <tdf/core/error.h>
#include <tdf/parts/part_segmentation.h>
#include <tdf/parts/part_target.h>
#include <tdf/render/scene_assets.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/train/optimize_run.h>
#include <tdf/train/part_gating.h>
#include <tdf/train/trainer.h>

#include "common/four_part_sphere.h"

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

// A trainer on a scene with n parts, past matching and one refinement iteration.
struct Refinement {
    SceneDescription description;
    std::unique_ptr<SceneAssets> assets;
    std::unique_ptr<PartTraining> parts;
    TrainingTarget target;
    std::unique_ptr<Trainer> trainer;
};

std::unique_ptr<GuidanceBackend> exemplar_backend(const std::string& tactile_image) {
    auto b = GuidanceBackend::create("exemplar_patch_match", Json::object());
    b->set_exemplars({load_tactile_map(tactile_image).normals});
    return b;
}

std::shared_ptr<Refinement> refinement(const std::string& scene, int parts) {
    auto r = std::make_shared<Refinement>();
    const SceneDescription two = load_scene(scene);
    r->assets = load_scene_assets(two);
    r->description = parts > 2 ? test::banded_sphere(two, r->assets->mesh,
                                                     (std::filesystem::temp_directory_path() /
                                                      ("tdf_banded_sphere_labels_" + std::to_string(parts) + ".txt"))
                                                         .string(),
                                                     parts)
                               : two;
    const RunConfig config = RunConfig::from_json(Json{{"iterations", 40}, {"init_iterations", 20}}, Json(),
                                                  Json{{"texture_size", 512}}, Json(), scene);
    r->target.mesh = &r->assets->mesh;
    r->target.scene = r->assets->scene.get();
    r->target.material = &r->assets->material;
    if (parts > 1) {
        r->parts = std::make_unique<PartTraining>(prepare_part_training(
            r->description, r->assets->mesh, r->assets->material, config.texture_size, config.gutter, scene));
        r->target.tactile_target_override = &r->parts->target;
        r->target.texel_parts = &r->parts->segmentation.texel_part;
        r->target.part_names = r->parts->segmentation.part_names;
    }
    r->trainer = std::make_unique<Trainer>(r->target, config, 0);
    r->trainer->set_guidance(GuidanceBackend::create("relief_shading", Json::object()),
                             parts > 1 ? nullptr : exemplar_backend(two.tactile_images.front()));
    if (parts > 1) {
        std::vector<PartGuidance> gates;
        for (const PartSpec& p : r->description.parts.parts) {
            gates.emplace_back();
            gates.back().name = p.name;
            gates.back().backend = exemplar_backend(p.tactile_images.front());
        }
        r->trainer->set_part_guidance(std::move(gates));
    }
    while (r->trainer->iteration() <= config.init_iterations + 1) r->trainer->step();
    return r;
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
        for (int n : {1, 2, 4, 8})
            benchmark::RegisterBenchmark(("refine/" + std::to_string(n) + "_parts").c_str(),
                                         [two, n](benchmark::State& state) {
                                             const auto r = refinement(two + "/scene.json", n);
                                             for (auto _ : state) benchmark::DoNotOptimize(r->trainer->step());
                                         })
                ->Unit(benchmark::kMillisecond)
                ->MeasureProcessCPUTime()
                ->UseRealTime()
                ->Iterations(3);
    } catch (const Error& e) {
        std::fprintf(stderr, "parts bench: %s\n", e.what());
        return 1;
    }
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
