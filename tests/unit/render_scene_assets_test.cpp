#include <tdf/core/error.h>
#include <tdf/atlas/uv_atlas.h>
#include <tdf/render/scene_assets.h>
#include <tdf/tactile/tactile_map.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace tdf;

namespace {

const std::vector<std::string> kAllPasses = {"albedo", "lambertian", "mask", "depth", "normal", "tangent", "uv",
                                             "tactile_normal", "shading_normal", "shading_normal_viewspace", "label"};

// Renders every pass of every view of a shipped scene at 64x64 and checks the images are
// finite, the object covers a sensible part of the picture and the albedo is not constant.
void render_shipped_scene(const std::string& scene, float min_coverage) {
    std::vector<std::string> overrides = {"image.width=64", "image.height=64", "passes=" + Json(kAllPasses).dump()};
    const SceneDescription d = load_scene(test::source_dir() + "/" + scene, overrides);
    const auto assets = load_scene_assets(d);
    const Renderer renderer(assets->mesh, *assets->scene, assets->material, assets->settings);
    ASSERT_FALSE(assets->views.empty());
    for (std::size_t k = 0; k < assets->views.size(); ++k) {
        const Frame frame = renderer.render_ssaa(assets->views[k].camera, assets->views[k].ssaa,
                                                 scene_light(d, assets->views[k], k), assets->passes);
        ASSERT_EQ(frame.images.size(), kAllPasses.size());
        for (const Image& image : frame.images) EXPECT_TRUE(image.all_finite()) << scene;
        double covered = 0;
        for (float m : frame.coverage.values()) covered += m;
        EXPECT_GT(covered / double(frame.coverage.pixel_count()), min_coverage) << scene << " view " << k;
        const Image& albedo = *frame.find(Pass::Albedo);
        float lo = 1e9f, hi = -1e9f;
        for (std::size_t i = 0; i < albedo.pixel_count(); ++i)
            if (frame.coverage.data()[i] == 1.f) {
                lo = std::min(lo, albedo.data()[3 * i]);
                hi = std::max(hi, albedo.data()[3 * i]);
            }
        EXPECT_GT(hi - lo, 0.05f) << scene << ": albedo looks constant";
    }
}

}  // namespace

TEST(SceneAssets, PebbleSphereRendersEveryPass) { render_shipped_scene("scenes/pebble_sphere/scene.json", 0.1f); }

TEST(SceneAssets, SpotRendersEveryPass) {
    TDF_REQUIRE_SHARED_DATA("meshes/spot/spot_triangulated.obj");
    render_shipped_scene("scenes/spot/scene.json", 0.05f);
}

TEST(SceneAssets, AvocadoGltfRendersEveryPass) {
    TDF_REQUIRE_SHARED_DATA("meshes/avocado_gltf/Avocado.gltf");
    render_shipped_scene("scenes/avocado/scene.json", 0.05f);
}

TEST(SceneAssets, MugRendersEveryPass) {
    TDF_REQUIRE_SHARED_DATA("meshes/mug/mug.obj");
    render_shipped_scene("scenes/mug/scene.json", 0.05f);
}

TEST(SceneAssets, MissingFilesAndUnknownPassesAreOneLineErrors) {
    const std::string scene = test::source_dir() + "/scenes/pebble_sphere/scene.json";
    auto error_of = [&](const std::vector<std::string>& overrides) -> std::string {
        try {
            load_scene_assets(load_scene(scene, overrides));
        } catch (const Error& e) {
            return e.what();
        }
        return "(no error)";
    };
    EXPECT_NE(error_of({"mesh=missing.obj"}).find("missing.obj' does not exist"), std::string::npos);
    EXPECT_NE(error_of({"tactile.images=[\"nope.png\"]"}).find("nope.png"), std::string::npos);
    EXPECT_NE(error_of({"albedo.image=gone.png"}).find("gone.png"), std::string::npos);
    const std::string unknown = error_of({"passes=[\"albedo\",\"glossy\"]"});
    EXPECT_NE(unknown.find("unknown pass 'glossy'"), std::string::npos) << unknown;
    EXPECT_NE(unknown.find("shading_normal_viewspace"), std::string::npos) << unknown;
    EXPECT_NE(error_of({"albedo.source=vertex_colors"}).find("vertex colours"), std::string::npos);
    // A NaN in a float image.
    Image nan_map(4, 4, 3, 0.5f);
    nan_map.at(1, 1, 1) = std::nanf("");
    const std::string nan_path = test::scratch_dir() + "/nan_map.exr";
    write_exr(nan_path, nan_map);
    EXPECT_NE(error_of({"tactile.images=[\"" + nan_path + "\"]"}).find("NaN"), std::string::npos);
}

TEST(SceneAssets, NormalMapDecodingFollowsSpec) {
    Image png(1, 1, 4);
    png.at(0, 0, 0) = 127.f / 255.f;
    png.at(0, 0, 1) = 128.f / 255.f;
    png.at(0, 0, 2) = 1.f;
    const Image n = decode_tactile_map(png, {}, "x.png").normals;
    ASSERT_EQ(n.channels(), 3);
    EXPECT_NEAR(n.at(0, 0, 0), -0.00392f, 1e-5f);  // spec 1.3: 127 -> -0.00392
    EXPECT_NEAR(n.at(0, 0, 1), 0.00392f, 1e-5f);
    EXPECT_FLOAT_EQ(n.at(0, 0, 2), 1.f);
    EXPECT_THROW(decode_tactile_map(Image(1, 1, 1), {}, "gray.png"), Error);
}

TEST(SceneAssets, NormalisedMeshExportsInTheFileCoordinatesAndReunwrapReplacesBadUvs) {
    // A quad strip far from the origin whose UVs all overlap (every face on the same UV triangle).
    const std::string folder = test::scratch_dir() + "/assets_reunwrap";
    std::filesystem::create_directories(folder);
    {
        std::ofstream obj(folder + "/strip.obj");
        obj << "v 100 10 5\nv 104 10 5\nv 108 10 5\nv 100 12 5\nv 104 12 5\nv 108 12 5\n"
               "vt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\n"
               "f 1/1 2/2 5/3\nf 1/1 5/2 4/3\nf 2/1 3/2 6/3\nf 2/1 6/2 5/3\n";
    }
    const std::string tactile = test::source_dir() + "/scenes/pebble_sphere/tactile_normal.png";
    std::ofstream(folder + "/scene.json") << "{\"mesh\": \"strip.obj\", \"normalize\": true, \"albedo\": {\"source\": "
                                             "\"constant\"}, \"tactile\": {\"images\": [\"" + tactile + "\"]}}";
    const auto kept = load_scene_assets(load_scene(folder + "/scene.json"));
    EXPECT_GT(count_uv_overlaps(kept->mesh), 0u);
    const Bounds3 b = compute_bounds(kept->mesh);
    EXPECT_NEAR(b.upper.x, 0.9f, 1e-5f);  // normalised for rendering and training
    const TriangleMesh exported = kept->export_mesh();
    EXPECT_NEAR(exported.positions[2].x, 108.f, 1e-3f);
    EXPECT_NEAR(exported.positions[5].y, 12.f, 1e-4f);
    EXPECT_NEAR(exported.positions[0].z, 5.f, 1e-4f);

    const auto fixed = load_scene_assets(load_scene(folder + "/scene.json", {"uv.reunwrap=true"}));
    ASSERT_TRUE(fixed->mesh.has_uvs());
    EXPECT_EQ(count_uv_overlaps(fixed->mesh), 0u);
    EXPECT_EQ(fixed->mesh.triangles.size(), kept->mesh.triangles.size());
    EXPECT_THROW(load_scene_assets(load_scene(folder + "/scene.json", {"uv.reunwrap=true", "label_map=\"" + tactile + "\""})),
                 Error);
}
