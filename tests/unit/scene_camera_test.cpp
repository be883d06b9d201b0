#include <tdf/scene/camera.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace tdf;

namespace {
void expect_vec_near(Vec3f a, Vec3f b, float tol = 1e-5f) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}
}  // namespace

TEST(Camera, OrbitPositionsFollowSpecFormula) {
    // Spec 2.1: x = r cos e sin a, y = -r sin e, z = r cos e cos a.
    const Camera front = Camera::orbit(0, 0, 2, 49.1f, 64, 64);
    expect_vec_near(front.position, {0, 0, 2});
    expect_vec_near(front.back, {0, 0, 1});
    expect_vec_near(front.right, {1, 0, 0});
    expect_vec_near(front.up, {0, 1, 0});
    expect_vec_near(Camera::orbit(0, 90, 2, 49.1f, 64, 64).position, {2, 0, 0});
    // Positive elevation is BELOW the equator.
    const Camera below = Camera::orbit(30, 45, 3, 49.1f, 64, 64);
    const float c = std::cos(radians(30.f)), s = std::sin(radians(30.f)), sa = std::sin(radians(45.f));
    expect_vec_near(below.position, {3 * c * sa, -3 * s, 3 * c * sa});
    EXPECT_LT(below.position.y, 0.f);
    // Orthonormal right-handed frame: right x up = back.
    expect_vec_near(cross(below.right, below.up), below.back);
    // Target offset.
    expect_vec_near(Camera::orbit(0, 0, 1, 50, 8, 8, {1, 2, 3}).position, {1, 2, 4});
}

TEST(Camera, ViewMatrixIsInverseOfPose) {
    const Camera cam = Camera::orbit(-20, 130, 2.5f, 49.1f, 64, 64);
    const Mat4f product = cam.view_matrix() * cam.pose_matrix();
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(product.m[i][j], i == j ? 1.f : 0.f, 1e-5f);
    const Vec4f origin = cam.view_matrix() * Vec4f(cam.position, 1.f);
    expect_vec_near(origin.xyz(), {0, 0, 0});
}

TEST(Camera, ProjectionMatricesMatchSpec) {
    // Spec 2.2 with fovy 49.1, n = 0.01, f = 100, aspect 1.
    const Camera cam = Camera::orbit(0, 0, 2, 49.1f, 512, 512);
    const float t = std::tan(radians(49.1f) / 2);
    const Mat4f p = cam.projection_matrix();
    EXPECT_NEAR(p.m[0][0], 1 / t, 1e-5f);
    EXPECT_NEAR(p.m[1][1], -1 / t, 1e-5f);
    EXPECT_NEAR(p.m[2][2], -(100.f + 0.01f) / (100.f - 0.01f), 1e-6f);
    EXPECT_NEAR(p.m[2][3], -2 * 100.f * 0.01f / (100.f - 0.01f), 1e-6f);
    EXPECT_EQ(p.m[3][2], -1.f);
    EXPECT_EQ(p.m[3][3], 0.f);
    Camera patch = Camera::tactile_patch({0, 0, 1}, {0, 0, 1}, 512, 512);
    patch.flip_rows = true;  // the reference's matrix has no y negation
    const Mat4f o = patch.projection_matrix();
    EXPECT_NEAR(o.m[0][0], 13.3333333f, 1e-4f);
    EXPECT_NEAR(o.m[1][1], 13.3333333f, 1e-4f);
    EXPECT_NEAR(o.m[2][2], -2.f / (100.f - 0.01f), 1e-7f);
    EXPECT_NEAR(o.m[2][3], -(100.f + 0.01f) / (100.f - 0.01f), 1e-6f);
    EXPECT_EQ(o.m[3][3], 1.f);
}

TEST(Camera, RaysProjectBackToTheirPixelCentres) {
    // nvdiffrast: pixel (i, j) centre at NDC ((2j+1)/W - 1, (2i+1)/H - 1).
    for (const bool ortho : {false, true}) {
        for (const bool flip : {false, true}) {
            Camera cam = ortho ? Camera::tactile_patch({0.2f, 0.1f, 0.5f}, safe_normalize({1, 2, 3}), 40, 30)
                               : Camera::orbit(10, -35, 2, 49.1f, 40, 30);
            cam.flip_rows = flip;
            const Mat4f pv = cam.projection_matrix() * cam.view_matrix();
            for (const auto& [i, j] : {std::pair{0, 0}, std::pair{7, 31}, std::pair{29, 39}}) {
                const Ray ray = cam.generate_ray(float(j) + 0.5f, float(i) + 0.5f);
                const Vec3f p = ray.origin + ray.direction * 1.5f;
                const Vec4f clip = pv * Vec4f(p, 1.f);
                EXPECT_NEAR(clip.x / clip.w, (2.f * j + 1) / 40.f - 1, 1e-4f) << ortho << flip;
                EXPECT_NEAR(clip.y / clip.w, (2.f * i + 1) / 30.f - 1, 1e-4f) << ortho << flip;
                // Direction has camera-space z = -1: t is the depth.
                EXPECT_NEAR(cam.world_to_camera_point(p).z, -1.5f, 1e-4f);
            }
        }
    }
}

TEST(Camera, UprightRowsAndReferencePatchFlip) {
    Camera cam = Camera::orbit(0, 0, 2, 49.1f, 64, 64);
    EXPECT_GT(cam.generate_ray(32, 0.5f).direction.y, 0.f);  // row 0 looks up
    Camera patch = Camera::tactile_patch({0, 0, 1}, {0, 0, 1}, 64, 64);
    EXPECT_GT(patch.generate_ray(32, 0.5f).origin.y, 0.f);
    patch.flip_rows = true;  // spec 2.2: row 0 is camera-down
    EXPECT_LT(patch.generate_ray(32, 0.5f).origin.y, 0.f);
}

TEST(Camera, TactilePatchLooksAlongMinusNormal) {
    const Vec3f n = safe_normalize({0.3f, -0.4f, 0.8f});
    const Camera cam = Camera::tactile_patch({0.1f, 0.2f, 0.3f}, n, 512, 512);
    expect_vec_near(cam.position, Vec3f{0.1f, 0.2f, 0.3f} + n * 0.1f);
    expect_vec_near(cam.back, n);
    EXPECT_EQ(cam.kind, Camera::Kind::Orthographic);
    // Window 0.15 wide: the corner ray starts 0.075 (less half a pixel) from the centre.
    const Ray corner = cam.generate_ray(0.f, 0.f);
    EXPECT_NEAR(dot(corner.origin - cam.position, cam.right), -0.075f, 1e-6f);
    EXPECT_NEAR(dot(corner.origin - cam.position, cam.up), 0.075f, 1e-6f);
}

TEST(Camera, VerticalNormalGetsTheLimitFrame) {
    // Spec 13.16: up_w x n vanishes. tdf takes the limit as n tilts toward +Z.
    const Camera top = Camera::tactile_patch({0, 1, 0}, {0, 1, 0}, 8, 8);
    expect_vec_near(top.right, {1, 0, 0});
    expect_vec_near(top.up, {0, 0, -1});
    const Camera near_top = Camera::tactile_patch({0, 1, 0}, safe_normalize({0, 1, 1e-3f}), 8, 8);
    expect_vec_near(near_top.right, top.right, 1e-3f);
    expect_vec_near(near_top.up, top.up, 1e-3f);
    const Camera bottom = Camera::tactile_patch({0, -1, 0}, {0, -1, 0}, 8, 8);
    const Camera near_bottom = Camera::tactile_patch({0, -1, 0}, safe_normalize({0, -1, 1e-3f}), 8, 8);
    expect_vec_near(bottom.right, near_bottom.right, 1e-3f);
    expect_vec_near(bottom.up, near_bottom.up, 1e-3f);
    expect_vec_near(cross(bottom.right, bottom.up), bottom.back);
}
