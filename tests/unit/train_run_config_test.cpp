// optimize.patch_resolution: "auto" in the texture schedule (sized from the learned maps' texel
// density), the reference's 512 in the reference schedule, a number when given one.
#include <tdf/core/error.h>
#include <tdf/scene/procedural_mesh.h>
#include <tdf/train/run_config.h>

#include <gtest/gtest.h>

namespace tdf {
namespace {

RunConfig config_from(const Json& optimize, const Json& schedule = Json(), const Json& exporting = Json()) {
    return RunConfig::from_json(optimize, Json(), exporting, Json(), "test", Json(), schedule);
}

TEST(RunConfig, PatchResolutionIsAutoOnlyWhereTheMapsAreLearned) {
    EXPECT_TRUE(config_from(Json::object()).patch_resolution_auto);
    const RunConfig reference = config_from(Json::object(), "reference");
    EXPECT_FALSE(reference.patch_resolution_auto);
    EXPECT_EQ(reference.patch_resolution, 512);
    const RunConfig given = config_from(Json{{"patch_resolution", 300}});
    EXPECT_FALSE(given.patch_resolution_auto);
    EXPECT_EQ(given.patch_resolution, 300);
    EXPECT_TRUE(config_from(Json{{"patch_resolution", "auto"}}, "reference").patch_resolution_auto);
    try {
        config_from(Json{{"patch_resolution", "large"}});
        FAIL() << "a word other than auto was accepted";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("optimize.patch_resolution must be a size in pixels or \"auto\""), std::string::npos)
            << message;
    }
    EXPECT_THROW(config_from(Json{{"patch_resolution", 0}}), Error);
}

TEST(RunConfig, AutoPatchResolutionGivesEveryMapTexelFourPixelsASide) {
    const TriangleMesh sphere = make_uv_sphere(1.0f, 64, 32);
    RunConfig config = config_from(Json::object());
    for (const int texture_size : {256, 512, 1024}) {
        config.texture_size = texture_size;
        const double texels = patch_window_texels(sphere, config);
        ASSERT_GT(texels, 0.0);
        const int pixels = auto_patch_resolution(sphere, config);
        EXPECT_EQ(pixels % 32, 0) << pixels;
        EXPECT_GE(pixels, 64);
        EXPECT_LE(pixels, 512);
        if (pixels > 64 && pixels < 512) {
            EXPECT_GE(pixels / texels, double(kAutoPatchPixelsPerTexel)) << texture_size;
            EXPECT_LT((pixels - 32) / texels, double(kAutoPatchPixelsPerTexel))
                << "not the smallest: " << texture_size;
        }
    }
    config.texture_size = 16384;  // texels finer than the reference's pixels: its 512
    EXPECT_EQ(auto_patch_resolution(sphere, config), 512);
    config.texture_size = 16;
    EXPECT_EQ(auto_patch_resolution(sphere, config), 64);
    TriangleMesh no_uvs = sphere;
    no_uvs.uv_triangles.clear();
    no_uvs.uvs.clear();
    config.texture_size = 1024;
    EXPECT_EQ(patch_window_texels(no_uvs, config), 0.0);
    EXPECT_EQ(auto_patch_resolution(no_uvs, config), 512);
}

}  // namespace
}  // namespace tdf
