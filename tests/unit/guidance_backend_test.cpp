#include <tdf/core/error.h>
#include <tdf/guidance/guidance_backend.h>
#include <tdf/guidance/guidance_frames.h>
#include <tdf/io/image_io.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace tdf {
namespace {

GuidanceRequest small_visual_request(int n = 2, int size = 8) {
    GuidanceRequest r;
    r.kind = GuidanceKind::Visual;
    for (int i = 0; i < n; ++i) {
        r.images.emplace_back(size, size, 3, 0.5f);
        r.control.emplace_back(size, size, 3, 0.5f);
        r.masks.emplace_back(size, size, 1, 1.0f);
    }
    return r;
}

TEST(GuidanceBae, BackgroundBecomesFlatNormalAndRedFlips) {
    Image n(2, 1, 3, 0.0f);
    const float s = 1.0f / std::sqrt(2.0f);
    n.at(1, 0, 0) = s;  // pointing right and toward the viewer
    n.at(1, 0, 2) = s;
    const Image bae = to_bae_control(n);
    EXPECT_FLOAT_EQ(bae.at(0, 0, 0), 0.5f);
    EXPECT_FLOAT_EQ(bae.at(0, 0, 1), 0.5f);
    EXPECT_FLOAT_EQ(bae.at(0, 0, 2), 1.0f);
    EXPECT_NEAR(bae.at(1, 0, 0), (1.0f - s) / 2.0f, 1e-6f);  // BAE red = left
    EXPECT_NEAR(bae.at(1, 0, 1), 0.5f, 1e-6f);
    EXPECT_NEAR(bae.at(1, 0, 2), (1.0f + s) / 2.0f, 1e-6f);
    const Image back = from_bae_control(bae);
    EXPECT_NEAR(back.at(1, 0, 0), s, 1e-6f);
    EXPECT_NEAR(back.at(1, 0, 2), s, 1e-6f);
}

TEST(GuidanceBae, NonUnitInputIsRenormalized) {
    Image n(1, 1, 3, 0.0f);
    n.at(0, 0, 1) = 0.25f;  // antialiased silhouette: short vector
    const Image bae = to_bae_control(n);
    EXPECT_NEAR(bae.at(0, 0, 1), 1.0f, 1e-6f);
    EXPECT_NEAR(bae.at(0, 0, 2), 0.5f, 1e-6f);
}

TEST(GuidanceRequestCheck, RejectsMismatchedShapes) {
    EXPECT_NO_THROW(validate_request(small_visual_request(), "test"));
    GuidanceRequest r = small_visual_request();
    r.masks.pop_back();
    EXPECT_THROW(validate_request(r, "test"), Error);
    r = small_visual_request();
    r.images[1] = Image(9, 8, 3);
    EXPECT_THROW(validate_request(r, "test"), Error);
    r = small_visual_request();
    r.kind = GuidanceKind::Tactile;  // tactile requests carry no control images
    EXPECT_THROW(validate_request(r, "test"), Error);
    r.control.clear();
    EXPECT_NO_THROW(validate_request(r, "test"));
    r.strength = 1.5;
    EXPECT_THROW(validate_request(r, "test"), Error);
    r = small_visual_request();
    r.images[0].at(1, 1, 1) = std::nanf("");
    EXPECT_THROW(validate_request(r, "test"), Error);
}

TEST(GuidanceRequestCheck, ResultMustMatchTheInputs) {
    const GuidanceRequest request = small_visual_request(2, 8);
    GuidanceResult result;
    result.refined = {Image(8, 8, 3, 1.0f), Image(8, 8, 3, 1.0f)};
    EXPECT_NO_THROW(validate_result(request, result, "test"));
    result.refined[1] = Image(8, 8, 1, 1.0f);
    EXPECT_THROW(validate_result(request, result, "test"), Error);
    result.refined.pop_back();
    EXPECT_THROW(validate_result(request, result, "test"), Error);
}

TEST(GuidanceFactory, NoneMeansDisabledAndUnknownNamesAreErrors) {
    EXPECT_EQ(GuidanceBackend::create("none", Json::object()), nullptr);
    EXPECT_EQ(GuidanceBackend::create("none", Json()), nullptr);
    EXPECT_THROW(GuidanceBackend::create("none", Json{{"gain", 1}}), Error);
    try {
        GuidanceBackend::create("controlnet", Json::object());
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("relief_shading"), std::string::npos) << e.what();
    }
    const auto relief = GuidanceBackend::create("relief_shading", Json::object());
    ASSERT_NE(relief, nullptr);
    EXPECT_EQ(relief->name(), "relief_shading");
    EXPECT_TRUE(relief->supports(GuidanceKind::Visual));
    EXPECT_FALSE(relief->supports(GuidanceKind::Tactile));
    relief->set_exemplars({Image(2, 2, 3, 0.0f)});  // ignored: relief shading uses no exemplars
    EXPECT_THROW(GuidanceBackend::create("relief_shading", Json{{"gian", 0.5}}), Error);  // misspelt key
    EXPECT_THROW(GuidanceBackend::create("external", Json::object()), Error);             // no command
    EXPECT_EQ(GuidanceBackend::names().front(), "none");
}

TEST(GuidanceFrames, WritesReferenceNamedFramesPerImage) {
    const std::string folder = test::scratch_dir() + "/guidance_frames";
    std::filesystem::remove_all(folder);
    GuidanceRequest request = small_visual_request(2, 4);
    GuidanceResult result;
    result.refined = {Image(4, 4, 3, 0.25f), Image(4, 4, 3, 0.75f)};
    const auto written = save_guidance_frames(folder, 150, request, result);
    EXPECT_EQ(written.size(), 8u);
    const Image refined = read_image(folder + "/controlnet_refined_images/00150_1.png");
    EXPECT_NEAR(refined.at(2, 2, 0), 0.75f, 1.0f / 255.0f);

    GuidanceRequest tactile;
    tactile.kind = GuidanceKind::Tactile;
    tactile.images = {Image(4, 4, 3, 0.0f)};
    tactile.masks = {Image(4, 4, 1, 0.0f)};
    save_guidance_frames(folder, 151, tactile, GuidanceResult{});
    // Normals are shown as (n + 1) / 2: a zero vector is mid grey.
    const Image normals = read_image(folder + "/rendered_perturb_normals/00151_0.png");
    EXPECT_NEAR(normals.at(0, 0, 2), 0.5f, 1.0f / 255.0f);
    EXPECT_FALSE(std::filesystem::exists(folder + "/rendered_guidance_perturb_normals"));
}

}  // namespace
}  // namespace tdf
