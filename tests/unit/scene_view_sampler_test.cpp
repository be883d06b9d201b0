#include <tdf/scene/procedural_mesh.h>
#include <tdf/scene/view_sampler.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace tdf;

TEST(ViewSampler, VisualViewsCoverTheReferenceRanges) {
    Rng rng(7);
    int min_e = 100, max_e = -100, min_a = 1000, max_a = -1000, ssaa_one = 0;
    const int n = 4000;
    for (int k = 0; k < n; ++k) {
        const VisualView v = sample_visual_view(rng);
        EXPECT_EQ(v.elevation_deg, std::floor(v.elevation_deg));
        min_e = std::min(min_e, int(v.elevation_deg));
        max_e = std::max(max_e, int(v.elevation_deg));
        min_a = std::min(min_a, int(v.azimuth_deg));
        max_a = std::max(max_a, int(v.azimuth_deg));
        EXPECT_GE(v.radius, 1.25f);
        EXPECT_LT(v.radius, 2.25f);
        EXPECT_NEAR(length(v.camera.position), v.radius, 1e-4f);
        EXPECT_GE(v.ssaa, 1.f);
        EXPECT_LE(v.ssaa, 2.f);
        EXPECT_EQ(v.internal_width, ssaa_internal_resolution(512, v.ssaa));
        EXPECT_EQ(v.internal_width % 8, 0);
        EXPECT_EQ(v.camera.width, v.internal_width);
        ssaa_one += v.ssaa == 1.f;
    }
    EXPECT_EQ(min_e, -30);
    EXPECT_EQ(max_e, 29);
    EXPECT_EQ(min_a, -180);
    EXPECT_EQ(max_a, 179);
    EXPECT_NEAR(double(ssaa_one) / n, 0.5, 0.05);  // s = 1 with probability 1/2
}

TEST(ViewSampler, InternalResolutionRoundsUpToMultiplesOf8) {
    EXPECT_EQ(ssaa_internal_resolution(512, 1.f), 512);
    EXPECT_EQ(ssaa_internal_resolution(512, 1.5f), 768);
    EXPECT_EQ(ssaa_internal_resolution(512, 1.01f), 520);  // ceil(517.12 / 8) * 8
    EXPECT_EQ(ssaa_internal_resolution(512, 2.f), 1024);
}

TEST(ViewSampler, PatchViewSitsAboveAVertex) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 16, 8);
    Rng rng(3);
    for (int k = 0; k < 50; ++k) {
        const Camera cam = sample_patch_view(rng, sphere);
        // The camera is v + 0.1 n for some vertex v with unit normal n = back.
        const Vec3f v = cam.position - cam.back * 0.1f;
        bool found = false;
        for (std::size_t i = 0; i < sphere.positions.size(); ++i)
            found |= length(sphere.positions[i] - v) < 1e-5f && length(sphere.normals[i] - cam.back) < 1e-5f;
        EXPECT_TRUE(found);
        EXPECT_EQ(cam.width, 512);
        EXPECT_FALSE(cam.flip_rows);
    }
}
