#include <tdf/core/error.h>
#include <tdf/render/shading.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace tdf;

TEST(Shading, HandedFrameEqualsSpecFormulaForPositiveW) {
    Rng rng(11);
    for (int k = 0; k < 100; ++k) {
        // Interpolated frames are not exactly orthogonal.
        const Vec3f N = safe_normalize({rng.normal(), rng.normal(), rng.normal()});
        const Vec3f T = safe_normalize(Vec3f{rng.normal(), rng.normal(), rng.normal()} * 0.2f +
                                       safe_normalize(cross(N, {0.3f, 1, 0.1f})));
        const Vec3f p = safe_normalize({rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.2f, 1)});
        const Vec3f B = safe_normalize(cross(T, N));
        const Vec3f spec = safe_normalize(T * p.x - B * p.y + N * p.z);  // spec 3.3
        const Vec3f ours = compose_shading_normal({T, N, 1.f}, p);
        EXPECT_NEAR(length(ours - spec), 0.f, 1e-5f);
        // w = -1 flips only the bitangent term.
        const Vec3f mirrored = compose_shading_normal({T, N, -1.f}, p);
        EXPECT_NEAR(length(mirrored - safe_normalize(T * p.x + B * p.y + N * p.z)), 0.f, 1e-5f);
    }
    EXPECT_EQ(length(compose_shading_normal({}, {0, 0, 1})), 0.f);  // background frame stays zero
}

TEST(Shading, Magic3dLightStaysNearTheCameraDirection) {
    Rng rng(5);
    for (const Vec3f cam : {Vec3f{1, 2, 3}, Vec3f{0, 0, 2}, Vec3f{0, 0, -2}, Vec3f{0, 3, 0}}) {
        for (int k = 0; k < 200; ++k) {
            const Vec3f light = sample_magic3d_light(rng, cam);
            ASSERT_TRUE(is_finite(light));
            EXPECT_GE(length(light), 3.f - 1e-4f);
            EXPECT_LT(length(light), 5.f + 1e-4f);
            // theta in [30, 90) degrees above the plane orthogonal to the camera direction.
            EXPECT_GE(dot(safe_normalize(light), safe_normalize(cam)), std::sin(kPi / 6) - 1e-4f);
        }
    }
    // Draw order: azimuth, elevation, distance.
    Rng a(9), b(9);
    const Vec3f light = sample_magic3d_light(a, {1, 0, 0});
    const float phi = b.uniform(-kPi, kPi), theta = b.uniform(kPi / 6, kPi / 2), d = b.uniform(3, 5);
    // Camera on +X: z_l = (1,0,0), x_l = (0,-1,0), y_l = z_l x x_l = (0,0,-1).
    const Vec3f expect = Vec3f{std::sin(theta), -std::cos(theta) * std::cos(phi), -std::cos(theta) * std::sin(phi)} * d;
    EXPECT_NEAR(length(light - expect), 0.f, 1e-5f);
}

TEST(Shading, ShadeFormulas) {
    EXPECT_FLOAT_EQ(training_shade({0, 0, 1}, {0, 0, 5}, {0, 0, 0}), 1.f);
    EXPECT_FLOAT_EQ(training_shade({0, 0, 1}, {0, 0, -5}, {0, 0, 0}), 0.5f);
    EXPECT_NEAR(training_shade({0, 0, 1}, {3, 0, 3}, {0, 0, 0}), 0.5f + 0.5f * std::sqrt(0.5f), 1e-6f);
    EXPECT_FLOAT_EQ(visualizer_shade({0, 0, 1}, {0, 0, 1}, 0.1f), 1.f);
    EXPECT_FLOAT_EQ(visualizer_shade({0, 0, 1}, {0, 0, -1}, 0.1f), 0.1f);
    const Vec3f d = orbit_direction(0, 90);
    EXPECT_NEAR(d.x, 1.f, 1e-6f);
    EXPECT_NEAR(orbit_direction(30, 0).y, -0.5f, 1e-6f);
}

TEST(ColorSpace, RawMultipliesStoredValuesAndSrgbShadesInLinearLight) {
    const Vec3f albedo{0.5f, 0.2f, 1.0f};
    // Raw: the reference's product, clamped.
    const Vec3f raw = lit_color(albedo, 0.5f, ColorSpace::Raw);
    EXPECT_FLOAT_EQ(raw.x, 0.25f);
    EXPECT_FLOAT_EQ(lit_color(albedo, 1.5f, ColorSpace::Raw).z, 1.0f);
    // sRGB: 0.5 decodes to 0.21404, half of it is 0.10702, which encodes to 0.36080.
    const Vec3f srgb = lit_color(albedo, 0.5f, ColorSpace::Srgb);
    EXPECT_NEAR(srgb.x, 0.36080f, 1e-4f);
    EXPECT_GT(srgb.y, raw.y) << "shading in linear light darkens mid-tones less than the raw product";
    // Full light shows the stored colour in both; the transfer functions invert each other.
    for (float c : {0.0f, 0.003f, 0.04f, 0.2f, 0.5f, 0.9f, 1.0f}) {
        EXPECT_NEAR(lit_color({c, c, c}, 1.0f, ColorSpace::Srgb).x, c, 2e-6f) << c;
        EXPECT_NEAR(srgb_to_linear(linear_to_srgb(c)), c, 2e-6f) << c;
    }
    EXPECT_EQ(parse_color_space("srgb"), ColorSpace::Srgb);
    EXPECT_STREQ(color_space_name(ColorSpace::Raw), "raw");
    EXPECT_THROW(parse_color_space("linear"), Error);
}
