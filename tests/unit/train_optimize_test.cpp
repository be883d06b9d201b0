// End-to-end checks of `tdf optimize` on the shipped pebble sphere at a small size: quality after
// the matching phase, determinism across thread counts, resume, exports and bad input.
#include <tdf/atlas/surface_texels.h>
#include <tdf/atlas/uv_raster.h>
#include <tdf/tactile/height_export.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/mesh/mesh_writer.h>
#include <tdf/scene/procedural_mesh.h>
#include <tdf/tactile/height_map.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/train/optimize_run.h>
#include <tdf/train/trainer.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace tdf;
namespace fs = std::filesystem;

namespace {

const std::string kScene = test::source_dir() + "/scenes/pebble_sphere/scene.json";

// A small configuration: every stage runs, in a few seconds.
std::vector<std::string> small_run(int iterations, int init_iterations) {
    return {"optimize.iterations=" + std::to_string(iterations),
            "optimize.init_iterations=" + std::to_string(init_iterations),
            "optimize.resolution=96",
            "optimize.patch_resolution=64",
            "optimize.batch_size=2",
            "optimize.patch_batch_size=2",
            "optimize.held_out_views=2",
            "optimize.held_out_patches=2",
            "export.texture_size=128",
            "export.turntable_views=1",
            "export.turntable_resolution=64",
            "guidance.tactile=none"};
}

std::string run_into(const std::string& folder, std::vector<std::string> overrides, int stop_after = 0,
                     bool resume = false) {
    OptimizeOptions options;
    options.scene_path = kScene;
    options.overrides = std::move(overrides);
    options.output_dir = test::scratch_dir() + "/" + folder;
    options.name = "pebble";
    options.stop_after = stop_after;
    options.resume = resume;
    if (!resume) fs::remove_all(options.output_dir);
    run_optimize(options);
    return options.output_dir + "/pebble";
}

std::string file_bytes(const std::string& path) { return read_text_file(path); }

}  // namespace

TEST(Optimize, MatchingPhaseReachesQualityThresholds) {
    // The field must reproduce the base albedo and the tactile map on views and patches it never
    // trained on (issue thresholds: 30 dB, 0.95).
    // 200 matching iterations at 96 px. Patch windows 4x wider than the reference's (0.075) so
    // that 400 patches see the whole sphere and held-out patches land on trained surface (one of
    // the reference's windows covers 0.3 % of this sphere). Measured: 30.96 dB, 0.9957.
    // The per-pixel optimizer (schedule=reference); the texture-space one is held to the issue's
    // texture-space thresholds in train_texture_space_test.cpp.
    auto overrides = small_run(200, 200);
    overrides.push_back("schedule=reference");
    overrides.push_back("optimize.patch_half_extent=0.3");
    overrides.push_back("optimize.batch_size=4");
    overrides.push_back("optimize.held_out_views=4");
    overrides.push_back("optimize.held_out_patches=4");
    const std::string base = run_into("quality", overrides);
    const Json report = parse_json(read_text_file(base + "_report.json"), base + "_report.json");
    const double psnr = report["quality"]["albedo_psnr_foreground_db"].get<double>();
    const double cosine = report["quality"]["tactile_mean_cosine"].get<double>();
    RecordProperty("albedo_psnr_db", std::to_string(psnr));
    RecordProperty("tactile_cosine", std::to_string(cosine));
    std::printf("held-out albedo PSNR %.2f dB, tactile mean cosine %.4f\n", psnr, cosine);
    EXPECT_GE(psnr, 30.0);
    EXPECT_GE(cosine, 0.95);
}

TEST(Optimize, ExportsReferenceFilesAndMaterialWithNormalMap) {
    const std::string base = run_into("exports", small_run(4, 2));
    for (const char* suffix : {".obj", ".mtl", ".glb", "_albedo.png", "_tactile_normal.png", "_albedo.exr",
                               "_tactile_normal.exr", "_config.json", "_losses.jsonl", "_loss_plot.svg",
                               "_report.json", "_initialized.obj", "_initialized_albedo.png", "_initialized_report.json"})
        EXPECT_TRUE(fs::exists(base + suffix)) << base + suffix;
    const std::string mtl = read_text_file(base + ".mtl");
    EXPECT_NE(mtl.find("map_Kd pebble_albedo.png"), std::string::npos) << mtl;
    EXPECT_NE(mtl.find("disp -mm "), std::string::npos) << mtl;
    EXPECT_NE(mtl.find("pebble_tactile_normal.png"), std::string::npos) << mtl;
    const Image albedo = read_image(base + "_albedo.png");
    EXPECT_EQ(albedo.width(), 128);
    // The exported mesh opens again with the same geometry.
    const TriangleMesh original = load_mesh(test::source_dir() + "/scenes/pebble_sphere/sphere.obj");
    const TriangleMesh exported = load_mesh(base + ".obj");
    EXPECT_EQ(exported.triangles.size(), original.triangles.size());
    EXPECT_FALSE(exported.albedo.empty());
    // Every iteration is logged with its weighted terms.
    const std::string log = read_text_file(base + "_losses.jsonl");
    EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 4);
    // Texture schedule: dense matching on texels, then rendered terms from the phase boundary on.
    EXPECT_NE(log.find("texture_albedo"), std::string::npos);
    EXPECT_NE(log.find("albedo_matching"), std::string::npos);
    EXPECT_NE(log.find("tactile_matching"), std::string::npos);
}

// The reference schedule (pixel evaluation: no texel atlas, so no texture-space report or spot
// strips) runs end to end through both phases and exports, its refinement with the albedo term
// (albedo_refine 500) beside visual guidance, at SSAA 2.
TEST(Optimize, ReferenceScheduleRunsThroughBothPhases) {
    std::vector<std::string> overrides = small_run(3, 1);
    overrides.push_back("schedule=reference");
    const std::string base = run_into("reference_schedule", overrides);
    for (const char* suffix : {".obj", "_albedo.png", "_tactile_normal.png", "_report.json", "_initialized_report.json"})
        EXPECT_TRUE(fs::exists(base + suffix)) << base + suffix;
    const std::string log = read_text_file(base + "_losses.jsonl");
    EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 3);
    EXPECT_NE(log.find("albedo_mean_colour"), std::string::npos) << log;
    EXPECT_NE(log.find("visual_guidance_l1"), std::string::npos) << log;
    const Json report = Json::parse(read_text_file(base + "_report.json"));
    EXPECT_FALSE(report.contains("colour")) << "pixel evaluation has no texture-space colour check";
}

// Issue 24's check, from the files alone: normals recomputed from the exported height map
// (central differences at its texel size, in mm) agree with the exported 8-bit normal map,
// mean cosine >= 0.995 over the whole texture; the report and the GLB carry the scale. At 512
// texels (0.0425 mm each here): at the 128 texels of small_run the pebbles' V-grooves are one
// or two texels wide, slopes that flip sign from texel to texel, which central differences of
// any height cannot show (measured 0.9930 there; 0.9986 at the scene's 1024 texels).
TEST(Optimize, ExportedHeightReproducesTheExportedNormalMap) {
    std::vector<std::string> overrides = small_run(4, 2);
    overrides.push_back("export.texture_size=512");
    const std::string base = run_into("height", overrides);
    const HeightMap height = read_height_map(base + "_height.exr");
    ASSERT_GT(height.mm_per_pixel, 0.0f);
    const Image encoded = read_image(base + "_tactile_normal.png");
    Image normals(encoded.width(), encoded.height(), 3);
    for (std::size_t i = 0; i < normals.values().size(); ++i) normals.values()[i] = encoded.values()[i] * 2.0f - 1.0f;
    const Image recomputed = normals_from_height(height.height, 1.0f / height.mm_per_pixel, false);
    double sum = 0;
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        const float* a = normals.pixel(int(p % std::size_t(normals.width())), int(p / std::size_t(normals.width())));
        const float* b = recomputed.data() + 3 * p;
        sum += (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    }
    const double cosine = sum / double(normals.pixel_count());
    std::printf("height map at %.4g mm per texel; recomputed normals: mean cosine %.5f\n",
                double(height.mm_per_pixel), cosine);
    EXPECT_GE(cosine, 0.995);
    const Json report = parse_json(read_text_file(base + "_report.json"), base);
    ASSERT_TRUE(report.contains("height_map")) << report.dump();
    EXPECT_GE(report["height_map"]["normal_consistency_cosine"].get<double>(), 0.995);
    EXPECT_GT(report["height_map"]["mm_per_unit"].get<double>(), 0.0);
    EXPECT_NEAR(report["height_map"]["mm_per_texel"].get<double>(), double(height.mm_per_pixel), 1e-6);
    const std::string glb = read_text_file(base + ".glb");
    EXPECT_NE(glb.find("\"tdf_height\""), std::string::npos);
    // The relief's ambient occlusion beside it, in the GLB's occlusionTexture: the pebbles'
    // grooves shade, the flat tops do not.
    EXPECT_NE(glb.find("\"occlusionTexture\""), std::string::npos);
    const Image ao = read_image(base + "_ao.png");
    EXPECT_EQ(ao.width(), height.height.width());
    const double visibility = report["height_map"]["ambient_occlusion"]["mean_visibility"].get<double>();
    EXPECT_GT(visibility, 0.7);
    EXPECT_LT(visibility, 0.99);
    // The charts meet level: across the sphere's u = 0/1 seam the exported heights step by far
    // less than the texture-space integration's (which knows nothing of the seam) do.
    const TriangleMesh mesh = load_mesh(base + ".obj");
    UvRaster raster = rasterize_uv(mesh, height.height.width());
    add_partial_texels(mesh, raster);  // as the bake
    const SurfaceTexels surface = surface_texels(mesh, raster);
    ASSERT_GT(surface.seam_links.size(), 100u);
    EXPECT_EQ(report["height_map"]["seam_links"].get<std::size_t>(), surface.seam_links.size());
    Image texture_space = integrate_normal_map(normals, false);
    for (float& v : texture_space.values()) v *= height.mm_per_pixel;
    const auto mean_step = [&](const Image& h) {
        double total = 0;
        for (const auto& [a, b] : surface.seam_links)
            total += std::abs(h.data()[surface.texels[std::size_t(a)]] - h.data()[surface.texels[std::size_t(b)]]);
        return total / double(surface.seam_links.size());
    };
    std::printf("mean height step across the seam: %.4f mm exported, %.4f mm texture-space\n",
                mean_step(height.height), mean_step(texture_space));
    EXPECT_LT(mean_step(height.height), 0.25 * mean_step(texture_space));
}

TEST(Optimize, SameSeedSameFilesOnOneAndTwoThreads) {
    std::string one, two;
    {
        ThreadLimit limit(1);
        one = run_into("threads1", small_run(5, 3));
    }
    {
        ThreadLimit limit(2);
        two = run_into("threads2", small_run(5, 3));
    }
    for (const char* suffix : {"_albedo.exr", "_tactile_normal.exr", "_albedo.png", ".obj", "_height.exr"})
        EXPECT_EQ(file_bytes(one + suffix), file_bytes(two + suffix)) << suffix;
}

TEST(Optimize, ResumedRunEndsWithTheSameFiles) {
    const std::string straight = run_into("straight", small_run(6, 3));
    const std::string sliced = run_into("sliced", small_run(6, 3), 2);
    EXPECT_FALSE(fs::exists(sliced + ".obj"));  // not finished yet
    run_into("sliced", small_run(6, 3), 4, true);
    run_into("sliced", small_run(6, 3), 0, true);
    for (const char* suffix : {"_albedo.exr", "_tactile_normal.exr", "_initialized_albedo.exr", ".obj"})
        EXPECT_EQ(file_bytes(straight + suffix), file_bytes(sliced + suffix)) << suffix;
}

TEST(Optimize, ResumeRefusesAnotherConfiguration) {
    run_into("mismatch", small_run(4, 2), 2);
    auto changed = small_run(4, 2);
    changed.push_back("optimize.learning_rate=0.02");
    try {
        run_into("mismatch", changed, 0, true);
        FAIL() << "resumed with another configuration";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("different scene or configuration"), std::string::npos) << e.what();
    }
}

TEST(Optimize, NonFiniteLossStopsAndNamesTheTerm) {
    auto overrides = small_run(6, 6);
    overrides.push_back("optimize.learning_rate=1e30");
    overrides.push_back("optimize.checkpoint_every=1");
    try {
        run_into("nan", overrides);
        FAIL() << "a diverging run finished";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("not finite"), std::string::npos) << message;
        EXPECT_NE(message.find("--resume"), std::string::npos) << message;
    }
    EXPECT_TRUE(fs::exists(test::scratch_dir() + "/nan/checkpoint.bin"));
}

TEST(Optimize, BadConfigurationIsAClearError) {
    const auto expect_error = [](std::vector<std::string> overrides, const std::string& needle) {
        try {
            run_into("bad", std::move(overrides));
            ADD_FAILURE() << "accepted: " << needle;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    };
    expect_error({"optimize.iterations=0"}, "optimize.iterations must be positive");
    expect_error({"optimize.itertions=5"}, "unknown key(s) 'itertions'");
    expect_error({"optimize.init_iterations=500"}, "init_iterations");
    expect_error({"tactile_layout.mode=physical"}, "mm_per_unit");
    expect_error({"guidance.visual=stable_diffusion"}, "unknown guidance backend");
    expect_error({"guidance.visul=none"}, "guidance: unknown key 'visul'");
    expect_error({"tactile.images=[]"}, "no tactile texture");
}

TEST(Optimize, PhysicalLayoutScaleFromAreas) {
    // A 2 x 2 unit quad mapped to the whole UV square: 2 units per UV unit. At 10 mm per unit a UV
    // unit spans 20 mm; a 100 px map at 0.05 mm/px spans 5 mm, so it repeats 4 times.
    TriangleMesh quad;
    quad.positions = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    quad.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    quad.uv_triangles = quad.triangles;
    EXPECT_NEAR(physical_tactile_uv_scale(quad, 10.0f, 100, 0.05f), 4.0f, 1e-5f);
}

// The documented real-data scenes (spot + avocado sample, glTF avocado + avocado sample, mug +
// crochet sample) run end to end at a small size and export finite maps.
class SharedDataScene : public ::testing::TestWithParam<const char*> {};

TEST_P(SharedDataScene, OptimizesAndExports) {
    TDF_REQUIRE_SHARED_DATA("meshes");
    const std::string scene = std::string("scenes/") + GetParam() + "/scene.json";
    OptimizeOptions options;
    options.scene_path = test::source_dir() + "/" + scene;
    options.overrides = small_run(4, 2);
    options.output_dir = test::scratch_dir() + "/shared_" + GetParam();
    fs::remove_all(options.output_dir);
    run_optimize(options);
    const std::string base = options.output_dir + "/" + GetParam();
    const Image albedo = read_image(base + "_albedo.exr");
    const Image normals = read_image(base + "_tactile_normal.exr");
    EXPECT_TRUE(albedo.all_finite());
    EXPECT_TRUE(normals.all_finite());
    EXPECT_TRUE(fs::exists(base + ".glb"));
    const Json report = parse_json(read_text_file(base + "_report.json"), base);
    EXPECT_TRUE(std::isfinite(report["quality"]["albedo_psnr_foreground_db"].get<double>()));
}

INSTANTIATE_TEST_SUITE_P(Optimize, SharedDataScene, ::testing::Values("spot", "avocado", "mug"));

TEST(Optimize, GreyHeightMapAsTactileMapIsAClearError) {
    const std::string grey = test::scratch_dir() + "/grey_height.png";
    Image image(16, 16, 3);
    for (std::size_t i = 0; i < image.pixel_count(); ++i) std::fill_n(image.data() + 3 * i, 3, float(i % 7) / 7.0f);
    write_png(grey, image);
    try {
        run_into("grey", {"tactile.images=[\"" + grey + "\"]"});
        FAIL() << "a height map was accepted as a normal map";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("grey height map"), std::string::npos) << e.what();
    }
}

TEST(Optimize, MeshWithoutUvsIsUnwrappedAutomatically) {
    TriangleMesh sphere = make_uv_sphere(0.8f, 16, 8, TangentMode::Handed);
    sphere.uvs.clear();
    sphere.uv_triangles.clear();
    const std::string folder = test::scratch_dir() + "/no_uvs";
    fs::create_directories(folder);
    write_obj(folder + "/sphere.obj", sphere, ObjMaterial{});
    const std::string scene = folder + "/scene.json";
    write_text_atomically(scene, "{\"mesh\": \"sphere.obj\", \"albedo\": {\"source\": \"constant\"}, "
                                 "\"tactile\": {\"images\": [\"" + test::source_dir() +
                                     "/scenes/pebble_sphere/tactile_normal.png\"]}}");
    OptimizeOptions options;
    options.scene_path = scene;
    options.overrides = small_run(2, 1);
    options.output_dir = folder + "/out";
    run_optimize(options);
    const TriangleMesh exported = load_mesh(options.output_dir + "/no_uvs.obj");
    EXPECT_TRUE(exported.has_uvs());
}

TEST(Optimize, UnwritableOutputIsAClearError) {
    OptimizeOptions options;
    options.scene_path = kScene;
    options.overrides = small_run(2, 1);
    options.output_dir = "/proc/tdf_cannot_write_here";
    EXPECT_THROW(run_optimize(options), Error);
}

TEST(Optimize, ExportsInTheInputCoordinatesAndEmbedsThePngFilesInTheGlb) {
    // A sphere of radius 30 around (100, -20, 5), trained normalised: the exports keep its size
    // and place, and the GLB holds the very bytes of the PNG maps beside it.
    TriangleMesh sphere = make_uv_sphere(30.f, 16, 8, TangentMode::Handed);
    for (Vec3f& p : sphere.positions) p += Vec3f{100.f, -20.f, 5.f};
    const std::string folder = test::scratch_dir() + "/placed";
    fs::create_directories(folder);
    write_obj(folder + "/placed_pebble.obj", sphere, ObjMaterial{});
    const std::string scene = folder + "/scene.json";
    write_text_atomically(scene, "{\"mesh\": \"placed_pebble.obj\", \"normalize\": true, \"albedo\": {\"source\": "
                                 "\"constant\"}, \"tactile\": {\"images\": [\"" + test::source_dir() +
                                     "/scenes/pebble_sphere/tactile_normal.png\"]}}");
    OptimizeOptions options;
    options.scene_path = scene;
    options.overrides = small_run(2, 1);
    options.output_dir = folder + "/out";
    options.name = "placed";
    fs::remove_all(options.output_dir);
    run_optimize(options);
    const std::string base = options.output_dir + "/placed";
    MeshLoadOptions load;
    load.load_textures = false;
    for (const char* file : {".obj", ".glb"}) {
        const TriangleMesh exported = load_mesh(base + file, load);
        const Bounds3 a = compute_bounds(exported), b = compute_bounds(sphere);
        EXPECT_LT(length(a.lower - b.lower), 1e-3f) << file;
        EXPECT_LT(length(a.upper - b.upper), 1e-3f) << file;
    }
    const std::string glb = read_text_file(base + ".glb");
    for (const char* map : {"_albedo.png", "_tactile_normal.png"}) {
        const std::string png = read_text_file(base + map);
        EXPECT_NE(glb.find(png), std::string::npos) << map << " is not embedded byte for byte";
    }
}

TEST(Optimize, PromptObjectComesFromTheSceneKeyTheMeshFileOrItsNodes) {
    SceneDescription d;
    TriangleMesh mesh;
    d.mesh = "/data/avocado_gltf/Avocado.gltf";
    EXPECT_EQ(object_name_for_prompt(d, mesh), "avocado");
    d.mesh = "/data/base_meshes/an_avocado_2/an_avocado_2_mesh.obj";  // the reference's layout
    EXPECT_EQ(object_name_for_prompt(d, mesh), "an avocado");
    d.mesh = "/data/meshes/spot/spot_triangulated.obj";
    EXPECT_EQ(object_name_for_prompt(d, mesh), "spot");
    d.mesh = "/downloads/WaterBottle.glb";
    EXPECT_EQ(object_name_for_prompt(d, mesh), "water bottle");
    d.mesh = "/gen/an_owl_RichDreamer/an_owl_RichDreamer_mesh.obj";  // generator names go, as in the reference
    EXPECT_EQ(object_name_for_prompt(d, mesh), "an owl");
    d.mesh = "/downloads/old_chair/scene.gltf";  // generic name: the one named node
    mesh.face_groups = {FaceGroup{"Teapot_01", "mesh0", ""}, FaceGroup{"Teapot_01", "mesh1", ""}};
    EXPECT_EQ(object_name_for_prompt(d, mesh), "teapot");
    mesh.face_groups.push_back(FaceGroup{"Lid", "mesh2", ""});  // several: the folder
    EXPECT_EQ(object_name_for_prompt(d, mesh), "old chair");
    d.object_name = "a ceramic mug";
    EXPECT_EQ(object_name_for_prompt(d, mesh), "a ceramic mug");
}

// Issue 24's round trip on a multi-part scene: every part is touched and compared with its own
// capture, at the pitch its layout lays the capture's pixels on the asset. two_part_sphere's
// export scale comes from its 128 px ribs map once over the atlas (10.88 mm per UV unit); the
// cap lays the same map 3 times (a pixel 10.88 / 384 mm), the base the 256 px pebbles twice
// (10.88 / 512 mm): relief scales 1/3 and 1/4 of GelSight Mini's 0.085 mm.
TEST(Optimize, RoundTripTouchesEveryPartAgainstItsOwnCapture) {
    OptimizeOptions options;
    options.scene_path = test::source_dir() + "/scenes/two_part_sphere/scene.json";
    options.overrides = small_run(4, 2);
    options.output_dir = test::scratch_dir() + "/parts_touch";  // not "roundtrip*": Checkpoint.RoundTripIsExact counts those
    options.name = "two";
    fs::remove_all(options.output_dir);
    run_optimize(options);
    const Json report = parse_json(read_text_file(options.output_dir + "/two_report.json"), "report");
    ASSERT_TRUE(report.contains("tactile_roundtrip")) << report.dump();
    const Json& trip = report["tactile_roundtrip"];
    ASSERT_EQ(trip["parts"].size(), 2u);
    const double expected_scale[] = {10.88 / 384.0 / 0.085, 10.88 / 512.0 / 0.085};
    int touches = 0;
    for (std::size_t k = 0; k < 2; ++k) {
        const Json& part = trip["parts"][k];
        EXPECT_EQ(part["name"], k == 0 ? "cap" : "base");
        EXPECT_NEAR(part["relief_scale"].get<double>(), expected_scale[k], 0.01 * expected_scale[k]);
        EXPECT_GT(part["touch_count"].get<int>(), 0);
        EXPECT_TRUE(fs::exists(options.output_dir + "/" + part["capture_preview"].get<std::string>()));
        touches += part["touch_count"].get<int>();
    }
    EXPECT_EQ(trip["touch_count"].get<int>(), touches);
    ASSERT_EQ(trip["touch_parts"].size(), std::size_t(touches));
    for (const Json& name : trip["touch_parts"]) EXPECT_TRUE(name == "cap" || name == "base");
}
