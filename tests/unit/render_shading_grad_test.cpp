#include <gtest/gtest.h>
#include <tdf/core/rng.h>
#include <tdf/render/shading.h>

#include "common/gradcheck.h"

using namespace tdf;
using test::check_gradient;

namespace {

Vec3f random_unit(Rng& rng) {
    return safe_normalize({rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
}

TangentFrame random_frame(Rng& rng, float handedness) {
    TangentFrame f;
    f.normal = random_unit(rng);
    const Vec3f t = random_unit(rng);
    f.tangent = safe_normalize(t - f.normal * dot(t, f.normal));
    f.handedness = handedness;
    return f;
}

Vec3f to_vec(const std::vector<float>& v) { return {v[0], v[1], v[2]}; }

}  // namespace

TEST(GradCheck, DetectsAWrongGradient) {
    const auto f = [](const std::vector<float>& x) { return double(x[0]) * x[0] + 3.0 * x[1]; };
    EXPECT_TRUE(check_gradient(f, {0.5f, 2.0f}, {1.0f, 3.0f}));
    EXPECT_FALSE(check_gradient(f, {0.5f, 2.0f}, {1.0f, 3.1f}));
}

TEST(ShadingGrad, TbnCompositionFollowsHandedTangentFrame) {
    TangentFrame f{{1, 0, 0}, {0, 0, 1}, 1.0f};
    // (0,1,0) in tangent space is N x T = +y for a right-handed chart, -y for a mirrored one.
    EXPECT_NEAR(compose_shading_normal(f, {0, 1, 0}).y, 1.0f, 1e-7f);
    f.handedness = -1.0f;
    EXPECT_NEAR(compose_shading_normal(f, {0, 1, 0}).y, -1.0f, 1e-7f);
    EXPECT_NEAR(compose_shading_normal(f, {0, 0, 1}).z, 1.0f, 1e-7f);
}

TEST(ShadingGrad, TbnCompositionBackwardMatchesFiniteDifferences) {
    Rng rng(3);
    for (int trial = 0; trial < 20; ++trial) {
        const TangentFrame f = random_frame(rng, trial % 2 ? 1.0f : -1.0f);
        const Vec3f p =
            safe_normalize({rng.uniform(-0.7f, 0.7f), rng.uniform(-0.7f, 0.7f), rng.uniform(0.3f, 1)});
        const Vec3f upstream(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
        const Vec3f d = compose_shading_normal_backward(f, p, upstream);
        EXPECT_TRUE(check_gradient(
            [&](const std::vector<float>& x) {
                return double(dot(compose_shading_normal(f, to_vec(x)), upstream));
            },
            {p.x, p.y, p.z},
            {d.x, d.y, d.z}))
            << "trial " << trial;
    }
}

TEST(ShadingGrad, ViewSpaceNormalBackwardMatchesFiniteDifferences) {
    Rng rng(4);
    for (int trial = 0; trial < 20; ++trial) {
        // A random rotation: an orthonormal frame from two random vectors.
        const Vec3f back = random_unit(rng);
        const Vec3f right = safe_normalize(cross(random_unit(rng), back));
        const ViewRotation r{right, cross(back, right), back};
        const Vec3f n = random_unit(rng) * rng.uniform(0.5f, 1.5f);  // not unit: exercises the normalize
        const Vec3f upstream(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
        const Vec3f d = view_space_normal_backward(r, n, upstream);
        EXPECT_TRUE(check_gradient(
            [&](const std::vector<float>& x) {
                return double(dot(view_space_normal(r, to_vec(x)), upstream));
            },
            {n.x, n.y, n.z},
            {d.x, d.y, d.z}))
            << "trial " << trial;
        // A rotation preserves length: the view normal of a unit normal is unit.
        EXPECT_NEAR(length(view_space_normal(r, safe_normalize(n))), 1.0f, 1e-6f);
    }
}

TEST(ShadingGrad, LambertShadeValuesAndAlbedoGradient) {
    // Light straight above a +z surface: n.l = 1 -> shade 1; facing away -> ambient 0.5.
    EXPECT_FLOAT_EQ(training_shade({0, 0, 1}, {0, 0, 4}, {0, 0, 0}), 1.0f);
    EXPECT_FLOAT_EQ(training_shade({0, 0, -1}, {0, 0, 4}, {0, 0, 0}), 0.5f);
    EXPECT_NEAR(training_shade({0, 0, 1}, {4, 0, 4}, {0, 0, 0}), 0.5f + 0.5f / std::sqrt(2.0f), 1e-6f);
    const float shade = training_shade(safe_normalize({0.2f, 0.1f, 1}), {1, 2, 4}, {0.1f, 0, 0});
    const Vec3f albedo(0.2f, 0.5f, 0.9f), upstream(0.3f, -1.0f, 0.7f);
    const Vec3f d = lambertian_backward(shade, upstream);
    EXPECT_TRUE(check_gradient(
        [&](const std::vector<float>& x) { return double(dot(lambertian(to_vec(x), shade), upstream)); },
        {albedo.x, albedo.y, albedo.z},
        {d.x, d.y, d.z}));
}
