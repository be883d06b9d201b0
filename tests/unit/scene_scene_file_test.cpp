#include <tdf/core/error.h>
#include <tdf/scene/procedural_mesh.h>
#include <tdf/scene/scene_file.h>
#include <tdf/scene/scene_views.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace tdf;

namespace {
std::string write_scene(const std::string& name, const std::string& text) {
    const std::string dir = test::scratch_dir() + "/scenes";
    std::filesystem::create_directories(dir);
    const std::string path = dir + "/" + name;
    std::ofstream(path) << text;
    return path;
}

std::string error_of(const std::string& path, const std::vector<std::string>& overrides = {}) {
    try {
        load_scene(path, overrides);
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}
}  // namespace

TEST(SceneFile, DefaultsAndRelativePaths) {
    const std::string path = write_scene("minimal.json", R"({"mesh": "meshes/cow.obj", "tactile": {"images": "t.png"}})");
    const SceneDescription s = load_scene(path);
    EXPECT_EQ(std::filesystem::path(s.mesh), std::filesystem::path(test::scratch_dir() + "/scenes/meshes/cow.obj"));
    ASSERT_EQ(s.tactile_images.size(), 1u);
    EXPECT_EQ(s.width, 512);
    EXPECT_EQ(s.shading, "visualizer");
    EXPECT_FLOAT_EQ(s.light.ambient, 0.1f);
    ASSERT_EQ(s.views.orbit.size(), 1u);  // one front view when none is given
    EXPECT_EQ(s.views.orbit[0].radius, 3.f);
    EXPECT_EQ(s.passes.size(), 3u);
    // Training shading defaults to the 0.5 ambient of spec 3.4.
    EXPECT_FLOAT_EQ(load_scene(path, {"shading=training"}).light.ambient, 0.5f);
}

TEST(SceneFile, OverridesParentsAndForeignSections) {
    write_scene("base.json", R"({"mesh": "a.obj", "image": {"width": 64, "height": 32}, "seed": 4,
                                 "optimize": {"iterations": 10}})");
    const std::string child = write_scene("child.json", R"({"parent": "base.json", "image": {"height": 48},
        "views": {"orbit": [{"elevation": 10, "azimuth": 20}], "turntable": {"count": 4}},
        "guidance": {"backend": "none"}})");
    const SceneDescription s = load_scene(child, {"seed=9", "views.radius=2.5"});
    EXPECT_EQ(s.width, 64);
    EXPECT_EQ(s.height, 48);
    EXPECT_EQ(s.seed, 9u);
    ASSERT_EQ(s.views.orbit.size(), 1u);
    EXPECT_EQ(s.views.orbit[0].radius, 2.5f);
    ASSERT_EQ(s.sections.count("optimize"), 1u);
    EXPECT_EQ(s.sections.at("optimize")["iterations"], 10);
    EXPECT_EQ(s.sections.count("guidance"), 1u);
    // Views: the orbit view then 4 turntable views at azimuth 0, 90, 180, 270.
    const std::vector<SceneView> views = make_scene_views(s, make_quad());
    ASSERT_EQ(views.size(), 5u);
    EXPECT_FLOAT_EQ(views[3].azimuth, 180.f);
    EXPECT_EQ(views[0].camera.width, 64);
    EXPECT_EQ(views[0].camera.height, 48);
    // The resolved JSON parses back to the same settings.
    const SceneDescription again = parse_scene(s.to_json(), child);
    EXPECT_EQ(again.to_json(), s.to_json());
}

TEST(SceneFile, SeededViewsAreReproducible) {
    const std::string path = write_scene("random.json", R"({"mesh": "a.obj", "seed": 5,
        "views": {"random": {"count": 3, "ssaa": true}, "patches": {"count": 2}}})");
    const SceneDescription s = load_scene(path);
    const TriangleMesh sphere = make_uv_sphere(1.f, 16, 8);
    const auto a = make_scene_views(s, sphere), b = make_scene_views(s, sphere);
    ASSERT_EQ(a.size(), 5u);
    for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_EQ(a[k].camera.position.x, b[k].camera.position.x);
        EXPECT_EQ(a[k].ssaa, b[k].ssaa);
    }
    EXPECT_EQ(a[3].camera.kind, Camera::Kind::Orthographic);
    EXPECT_NE(a[3].camera.position.x, a[4].camera.position.x);
}

TEST(SceneFile, BadInputNamesTheFileAndKey) {
    const std::string ok = write_scene("ok.json", R"({"mesh": "a.obj"})");
    EXPECT_NE(error_of(write_scene("typo.json", R"({"mesh": "a.obj", "imagee": {}})")).find("'imagee'"),
              std::string::npos);
    EXPECT_NE(error_of(write_scene("nested.json", R"({"mesh": "a.obj", "image": {"widht": 3}})")).find("widht"),
              std::string::npos);
    EXPECT_NE(error_of(ok, {"image.width=0"}).find("image size 0x512"), std::string::npos);
    EXPECT_NE(error_of(ok, {"shading=fancy"}).find("valid: training, visualizer"), std::string::npos);
    EXPECT_NE(error_of(ok, {"ssaa=0.5"}).find("ssaa"), std::string::npos);
    EXPECT_NE(error_of(ok, {"views.fovy=-1"}).find("fovy"), std::string::npos);
    EXPECT_NE(error_of(ok, {"light.mode=sun"}).find("light"), std::string::npos);
    EXPECT_NE(error_of(ok, {"novalue"}).find("key=value"), std::string::npos);
    EXPECT_NE(error_of(write_scene("nomesh.json", "{}")).find("'mesh'"), std::string::npos);
    EXPECT_NE(error_of(write_scene("broken.json", "{\"mesh\": ")).find("broken.json"), std::string::npos);
    EXPECT_NE(error_of(test::scratch_dir() + "/absent.json").find("absent.json"), std::string::npos);
    for (const auto& message : {error_of(ok, {"image.width=0"}), error_of(ok, {"shading=fancy"})})
        EXPECT_NE(message.find("ok.json"), std::string::npos) << message;
}

TEST(SceneFile, LimitsAreCheckedBeforeAnyWork) {
    const std::string ok = write_scene("limits.json", R"({"mesh": "a.obj"})");
    const std::string views = error_of(ok, {"views.random.count=100000000"});
    EXPECT_NE(views.find("limits.json.views: 100000000 views in all"), std::string::npos) << views;
    EXPECT_NE(views.find("limit of 10000"), std::string::npos) << views;
    EXPECT_NE(error_of(ok, {"views.turntable.count=9000", "views.patches.count=2000"}).find("11000 views"),
              std::string::npos);
    EXPECT_NO_THROW(load_scene(ok, {"views.turntable.count=10000"}));
    const std::string ssaa = error_of(ok, {"ssaa=4", "image.width=16384", "image.height=16384"});
    EXPECT_NE(ssaa.find("at ssaa 4 renders 65536 pixels wide, over the limit of 16384"), std::string::npos)
        << ssaa;
    EXPECT_NO_THROW(load_scene(ok, {"ssaa=4", "image.width=4096", "image.height=4096"}));
    // Random views' SSAA factor reaches 2.
    EXPECT_NE(
        error_of(ok, {"image.width=16384", "views.random.count=1", "views.random.ssaa=true"}).find("ssaa 2"),
        std::string::npos);
    // An int key given a value that does not fit an int is an error, not a wrapped number.
    EXPECT_NE(error_of(ok, {"image.width=4294967808"}).find("'width' must be an integer in"),
              std::string::npos);
}

TEST(SceneFile, SeedTakesTheFullUnsignedRange) {
    const std::string ok = write_scene("seed.json", R"({"mesh": "a.obj"})");
    EXPECT_EQ(load_scene(ok, {"seed=18446744073709551615"}).seed, 18446744073709551615ull);
    EXPECT_EQ(load_scene(ok, {"seed=18446744073709551615"}).to_json()["seed"].get<std::uint64_t>(),
              18446744073709551615ull);
    const std::string negative = error_of(ok, {"seed=-1"});
    EXPECT_NE(negative.find("'seed' must be an integer in [0, 18446744073709551615], got -1"),
              std::string::npos)
        << negative;
    EXPECT_NE(error_of(ok, {"seed=18446744073709551616"}).find("seed"), std::string::npos);
    EXPECT_NE(error_of(write_scene("dupseed.json", R"({"mesh": "a.obj", "seed": 1, "seed": 2})"))
                  .find("dupseed.json: duplicate key 'seed'"),
              std::string::npos);
}
