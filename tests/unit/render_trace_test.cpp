#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/render/trace.h>
#include <tdf/scene/procedural_mesh.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

using namespace tdf;

TEST(Trace, QuadFacingTheCameraGivesExactAttributes) {
    const TriangleMesh quad = make_quad(1.f);
    const EmbreeScene scene(quad);
    const Camera cam = Camera::orbit(0, 0, 2, 90, 64, 64);  // tan(45) = 1: image spans [-2, 2]
    const GBuffer g = trace_gbuffer(scene, quad, cam);
    ASSERT_EQ(g.width, 64);
    // The quad covers the central half of the image: 32 x 32 pixels.
    float covered = 0;
    for (float m : g.mask) covered += m;
    EXPECT_EQ(covered, 32.f * 32.f);
    const std::size_t i = g.index(40, 20);  // pixel centre (40.5, 20.5) -> world (0.53125, 0.71875)
    ASSERT_EQ(g.mask[i], 1.f);
    EXPECT_NEAR(g.position[i].x, 0.53125f, 1e-5f);
    EXPECT_NEAR(g.position[i].y, 0.71875f, 1e-5f);
    EXPECT_NEAR(g.depth[i], 2.f, 1e-5f);
    EXPECT_NEAR(g.normal[i].z, 1.f, 1e-6f);
    EXPECT_NEAR(g.tangent[i].x, 1.f, 1e-6f);
    EXPECT_EQ(g.handedness[i], 1.f);
    EXPECT_NEAR(g.uv[i].x, (0.53125f + 1) / 2, 1e-5f);
    EXPECT_NEAR(g.uv[i].y, (0.71875f + 1) / 2, 1e-5f);
    // One pixel is 4/64 world units = 1/32 in u; moving down the image lowers v.
    EXPECT_NEAR(g.duv_dx[i].x, 1.f / 32, 1e-6f);
    EXPECT_NEAR(g.duv_dx[i].y, 0.f, 1e-6f);
    EXPECT_NEAR(g.duv_dy[i].y, -1.f / 32, 1e-6f);
    const std::size_t bg = g.index(2, 2);
    EXPECT_EQ(g.mask[bg], 0.f);
    EXPECT_EQ(g.triangle[bg], -1);
    EXPECT_EQ(g.depth[bg], 0.f);
}

TEST(Trace, UvDerivativesMatchFiniteDifferencesOnASphere) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 64, 32);
    const EmbreeScene scene(sphere);
    const Camera cam = Camera::orbit(-20, 30, 3, 49.1f, 256, 256);
    const GBuffer g = trace_gbuffer(scene, sphere, cam);
    int checked = 0;
    for (int y = 60; y < 200; y += 7)
        for (int x = 60; x < 200; x += 7) {
            const std::size_t i = g.index(x, y), r = g.index(x + 1, y), d = g.index(x, y + 1);
            if (!g.mask[i] || g.triangle[r] != g.triangle[i] || g.triangle[d] != g.triangle[i]) continue;
            // Within one triangle UV is a rational function of the pixel; a 1-pixel difference
            // agrees with the analytic derivative to second order.
            const Vec2f fx = g.uv[r] - g.uv[i], fy = g.uv[d] - g.uv[i];
            const float scale = std::fabs(g.duv_dx[i].x) + std::fabs(g.duv_dx[i].y) + std::fabs(g.duv_dy[i].x) +
                                std::fabs(g.duv_dy[i].y);
            EXPECT_NEAR(fx.x, g.duv_dx[i].x, 0.05f * scale);
            EXPECT_NEAR(fx.y, g.duv_dx[i].y, 0.05f * scale);
            EXPECT_NEAR(fy.x, g.duv_dy[i].x, 0.05f * scale);
            EXPECT_NEAR(fy.y, g.duv_dy[i].y, 0.05f * scale);
            ++checked;
        }
    EXPECT_GT(checked, 50);
}

TEST(Trace, NearPlaneIsPlanarAndBackFacesAreVisible) {
    const TriangleMesh quad = make_quad(1.f);
    const EmbreeScene scene(quad);
    // From behind (azimuth 180) the quad is still visible: no culling.
    const GBuffer back = trace_gbuffer(scene, quad, Camera::orbit(0, 180, 2, 49.1f, 16, 16));
    EXPECT_EQ(back.mask[back.index(8, 8)], 1.f);
    // Ortho camera 0.005 in front of the surface: inside the near plane, clipped.
    const GBuffer clipped = trace_gbuffer(scene, quad, Camera::tactile_patch({0, 0, 0}, {0, 0, 1}, 16, 16, 0.005f));
    EXPECT_EQ(clipped.mask[clipped.index(8, 8)], 0.f);
    const GBuffer seen = trace_gbuffer(scene, quad, Camera::tactile_patch({0, 0, 0}, {0, 0, 1}, 16, 16, 0.02f));
    EXPECT_EQ(seen.mask[seen.index(8, 8)], 1.f);
    EXPECT_NEAR(seen.depth[seen.index(8, 8)], 0.02f, 1e-6f);
    // Perspective near plane is planar: a corner pixel whose RADIAL distance exceeds 0.01 is
    // still clipped when the plane is 0.009 in front.
    Camera wide = Camera::orbit(0, 0, 0.009f, 120, 16, 16);
    const GBuffer g = trace_gbuffer(scene, quad, wide);
    for (float m : g.mask) EXPECT_EQ(m, 0.f);
}

TEST(Trace, MatchesBareClosestHitTracing) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 48, 24);
    const EmbreeScene scene(sphere);
    const Camera cam = Camera::orbit(10, 40, 2.5f, 49.1f, 100, 70);
    const GBuffer g = trace_gbuffer(scene, sphere, cam);
    std::vector<float> t;
    const std::size_t hits = trace_closest_hits(scene, cam, t);
    std::size_t mask_hits = 0;
    for (std::size_t i = 0; i < g.pixel_count(); ++i) {
        mask_hits += g.mask[i] > 0;
        EXPECT_EQ(t[i], g.depth[i]);
    }
    EXPECT_EQ(hits, mask_hits);
    // Single-ray tracing agrees with the packets.
    const Ray ray = cam.generate_ray(50.5f, 35.5f);
    const RayHit hit = trace_ray(scene, ray);
    EXPECT_EQ(hit.triangle, g.triangle[g.index(50, 35)]);
    EXPECT_NEAR(hit.t, g.depth[g.index(50, 35)], 1e-5f);
}

// The shading-only G-buffer (the texture-space optimizer's iterations) holds the same shading
// attributes, bit for bit, and no triangle ids, barycentrics or depth; reusing it for a full
// G-buffer brings them back.
TEST(Trace, ShadingFieldsEqualTheFullGBuffersAndLeaveOutIdsAndDepth) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 48, 24);
    const EmbreeScene scene(sphere);
    const Camera cam = Camera::orbit(10, 40, 2.5f, 49.1f, 100, 70);
    const GBuffer full = trace_gbuffer(scene, sphere, cam);
    GBuffer lean;
    trace_gbuffer(scene, sphere, cam, lean, GBufferFields::Shading);
    EXPECT_FALSE(lean.has_ids_and_depth());
    EXPECT_TRUE(lean.triangle.empty() && lean.barycentric.empty() && lean.depth.empty());
    ASSERT_EQ(lean.pixel_count(), full.pixel_count());
    std::size_t hits = 0;
    const auto same2 = [](Vec2f a, Vec2f b) { return a.x == b.x && a.y == b.y; };
    const auto same3 = [](Vec3f a, Vec3f b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
    for (std::size_t i = 0; i < full.pixel_count(); ++i) {
        hits += full.mask[i] > 0.f;
        ASSERT_EQ(lean.mask[i], full.mask[i]) << i;
        ASSERT_TRUE(same3(lean.position[i], full.position[i]) && same3(lean.normal[i], full.normal[i]) &&
                    same3(lean.tangent[i], full.tangent[i]) && lean.handedness[i] == full.handedness[i] &&
                    same2(lean.uv[i], full.uv[i]) && same2(lean.duv_dx[i], full.duv_dx[i]) &&
                    same2(lean.duv_dy[i], full.duv_dy[i]))
            << "pixel " << i;
    }
    EXPECT_GT(hits, full.pixel_count() / 4);
    trace_gbuffer(scene, sphere, cam, lean);
    ASSERT_TRUE(lean.has_ids_and_depth());
    ASSERT_EQ(lean.depth.size(), full.depth.size());
    for (std::size_t i = 0; i < full.pixel_count(); ++i) {
        ASSERT_EQ(lean.triangle[i], full.triangle[i]);
        ASSERT_EQ(lean.depth[i], full.depth[i]);
    }
}

// The full-frame G-buffer is the renderer's tiles in lanes (trace_tile_lanes) written out
// (stream_gbuffer_tile): every pixel is exactly one lane's and holds its bits, with and without
// tangents and UVs, on tiles cut short by the image's edges (100 x 70 is no multiple of 64 x 4),
// background included; with 8-wide packets (AVX2 machines' 4 x 2 blocks) too.
TEST(Trace, TileLanesEqualTheFullGBufferBitForBit) {
    TriangleMesh full_mesh = make_uv_sphere(1.f, 48, 24);
    TriangleMesh no_tangents = full_mesh;
    no_tangents.tangents.clear();
    no_tangents.tangent_triangles.clear();
    TriangleMesh no_uvs = no_tangents;
    no_uvs.uvs.clear();
    no_uvs.uv_triangles.clear();
    const auto bits = [](const float* a, const float* b) { return std::memcmp(a, b, sizeof(float)) == 0; };
    for (const auto& [mesh, width] : {std::pair{&full_mesh, PacketWidth::Native},
                                      std::pair{&no_tangents, PacketWidth::Native},
                                      std::pair{&no_uvs, PacketWidth::Native},
                                      std::pair{&full_mesh, PacketWidth::Eight}}) {
        const EmbreeScene scene(*mesh, width);
        const Camera cam = Camera::orbit(10, 40, 2.5f, 49.1f, 100, 70);
        const GBuffer g = trace_gbuffer(scene, *mesh, cam);
        std::vector<int> seen(g.pixel_count(), 0);
        std::size_t hits = 0;
        auto lanes = std::make_unique<GBufferLanes>();
        for (int y0 = 0; y0 < cam.height; y0 += kTraceTileHeight)
            for (int x0 = 0; x0 < cam.width; x0 += kTraceTileWidth) {
                const int x1 = std::min(x0 + kTraceTileWidth, cam.width),
                          y1 = std::min(y0 + kTraceTileHeight, cam.height);
                GBufferLanes& l = *lanes;
                trace_tile_lanes(scene, *mesh, cam, x0, y0, x1, y1, l);
                ASSERT_EQ(l.width, x1 - x0);
                ASSERT_EQ(l.height, y1 - y0);
                for (int k = 0; k < l.count; ++k) {
                    if (l.pixel[k] < 0) {
                        ASSERT_EQ(l.mask[k], 0.f);
                        continue;
                    }
                    const std::size_t i = g.index(x0 + l.pixel[k] % l.width, y0 + l.pixel[k] / l.width);
                    ++seen[i];
                    hits += l.mask[k] > 0.f;
                    const auto same = [&](const float* lane, const float* pixel) {
                        return bits(lane + k, pixel);
                    };
                    ASSERT_TRUE(same(l.mask, &g.mask[i]) && l.triangle[k] == g.triangle[i] &&
                                same(l.b1, &g.barycentric[i].x) && same(l.b2, &g.barycentric[i].y) &&
                                same(l.depth, &g.depth[i]))
                        << "pixel " << i;
                    ASSERT_TRUE(same(l.qx, &g.position[i].x) && same(l.qy, &g.position[i].y) &&
                                same(l.qz, &g.position[i].z) && same(l.nx, &g.normal[i].x) &&
                                same(l.ny, &g.normal[i].y) && same(l.nz, &g.normal[i].z))
                        << "pixel " << i;
                    ASSERT_TRUE(same(l.tx, &g.tangent[i].x) && same(l.ty, &g.tangent[i].y) &&
                                same(l.tz, &g.tangent[i].z) && same(l.w, &g.handedness[i]))
                        << "pixel " << i;
                    ASSERT_TRUE(same(l.u, &g.uv[i].x) && same(l.v, &g.uv[i].y) &&
                                same(l.du_dx, &g.duv_dx[i].x) && same(l.dv_dx, &g.duv_dx[i].y) &&
                                same(l.du_dy, &g.duv_dy[i].x) && same(l.dv_dy, &g.duv_dy[i].y))
                        << "pixel " << i;
                }
            }
        for (std::size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], 1) << "pixel " << i;
        EXPECT_GT(hits, g.pixel_count() / 4);
        EXPECT_LT(hits, g.pixel_count());
    }
}

// Every pixel of the full-frame G-buffer holds the plain per-pixel interpolation of its hit's
// triangle corners at its barycentrics (written out here in scalar form, independently of the
// vectorised lanes), background pixels exactly what clear_pixel leaves; a reused G-buffer holding
// another view's values, on an image whose rows start off the 16-byte grid (67 wide: the
// writer's scalar path), ends up with the bits of a fresh one; with 8-wide packets too.
TEST(Trace, FullGBufferHoldsThePlainInterpolationOfEachHit) {
    TriangleMesh sphere = make_uv_sphere(1.f, 48, 24);
    ASSERT_FALSE(sphere.tangents.empty());
    ASSERT_TRUE(sphere.has_uvs());
    // Mirrored corners here and there: the interpolated handedness changes sign within triangles.
    for (std::size_t k = 0; k < sphere.tangents.size(); k += 3) sphere.tangents[k].w = -1.f;
    for (const auto& [width, height, packets] : {std::tuple{100, 70, PacketWidth::Native},
                                                 std::tuple{67, 45, PacketWidth::Native},
                                                 std::tuple{67, 45, PacketWidth::Eight}}) {
        const EmbreeScene scene(sphere, packets);
        const Camera cam = Camera::orbit(10, 40, 2.5f, 49.1f, width, height);
        GBuffer g;
        trace_gbuffer(scene, sphere, Camera::orbit(200, -30, 3.f, 30.f, 120, 90), g);  // another view first
        trace_gbuffer(scene, sphere, cam, g);
        const GBuffer fresh = trace_gbuffer(scene, sphere, cam);
        ASSERT_EQ(g.pixel_count(), std::size_t(width) * std::size_t(height));
        ASSERT_EQ(std::memcmp(g.position.data(), fresh.position.data(), g.pixel_count() * sizeof(Vec3f)), 0);
        ASSERT_EQ(std::memcmp(g.duv_dy.data(), fresh.duv_dy.data(), g.pixel_count() * sizeof(Vec2f)), 0);
        std::size_t hits = 0, negative = 0;
        for (std::size_t i = 0; i < g.pixel_count(); ++i) {
            const int f = g.triangle[i];
            if (g.mask[i] == 0.f) {
                ASSERT_EQ(f, -1) << "pixel " << i;
                for (float z :
                     {g.barycentric[i].x, g.depth[i], g.position[i].x, g.normal[i].y, g.tangent[i].z})
                    ASSERT_EQ(z, 0.f) << "pixel " << i;
                for (float z : {g.handedness[i], g.uv[i].x, g.duv_dx[i].y, g.duv_dy[i].x})
                    ASSERT_EQ(z, 0.f) << "pixel " << i;
                continue;
            }
            ++hits;
            ASSERT_EQ(g.mask[i], 1.f);
            ASSERT_GE(f, 0);
            ASSERT_LT(std::size_t(f), sphere.triangles.size());
            const float b1 = g.barycentric[i].x, b2 = g.barycentric[i].y, b0 = 1.f - b1 - b2;
            const auto mix = [&](const auto& values, const Vec3i& corners) {
                return values[std::size_t(corners.x)] * b0 + values[std::size_t(corners.y)] * b1 +
                       values[std::size_t(corners.z)] * b2;
            };
            const Vec3i& tri = sphere.triangles[std::size_t(f)];
            const Vec3i& tt = sphere.tangent_triangles[std::size_t(f)];
            const Vec3i& ut = sphere.uv_triangles[std::size_t(f)];
            const Vec3f p = mix(sphere.positions, tri), n = safe_normalize(mix(sphere.normals, tri));
            const Vec3f t = sphere.tangents[std::size_t(tt.x)].xyz() * b0 +
                            sphere.tangents[std::size_t(tt.y)].xyz() * b1 +
                            sphere.tangents[std::size_t(tt.z)].xyz() * b2;
            const Vec2f uv = mix(sphere.uvs, ut);
            const float tol = 2e-6f;
            EXPECT_NEAR(g.position[i].x, p.x, tol);
            EXPECT_NEAR(g.position[i].y, p.y, tol);
            EXPECT_NEAR(g.position[i].z, p.z, tol);
            EXPECT_NEAR(dot(g.normal[i], n), 1.f, tol) << "pixel " << i;
            EXPECT_NEAR(dot(g.tangent[i], safe_normalize(t)), 1.f, tol) << "pixel " << i;
            const float w = sphere.tangents[std::size_t(tt.x)].w * b0 +
                            sphere.tangents[std::size_t(tt.y)].w * b1 +
                            sphere.tangents[std::size_t(tt.z)].w * b2;
            if (std::abs(w) > 1e-4f) {
                ASSERT_EQ(g.handedness[i], w < 0.f ? -1.f : 1.f) << "pixel " << i;
            }
            negative += g.handedness[i] < 0.f;
            EXPECT_NEAR(g.uv[i].x, uv.x, tol);
            EXPECT_NEAR(g.uv[i].y, uv.y, tol);
            EXPECT_NEAR(g.depth[i], dot(cam.back, cam.position - p), 1e-5f);  // -z_cam
        }
        EXPECT_GT(hits, g.pixel_count() / 4);
        EXPECT_LT(hits, g.pixel_count());
        EXPECT_GT(negative, hits / 10);
        EXPECT_LT(negative, hits - hits / 10);
    }
}

// The 4 x 2 packets of AVX2 machines give the G-buffer the 4 x 4 packets of AVX-512 machines give,
// bit for bit (on a machine with AVX-512, which traces both; elsewhere both are 8 wide): the same
// rays, hits and per-hit arithmetic, so a run does not depend on the packet width.
TEST(Trace, EightWidePacketsGiveTheSixteenWideBits) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 120, 60);
    const EmbreeScene native(sphere), eight(sphere, PacketWidth::Eight);
    EXPECT_FALSE(eight.native_packet16());
    for (int k = 0; k < 3; ++k) {
        const Camera cam =
            Camera::orbit(10.f + 50.f * float(k), 40.f - 25.f * float(k), 2.5f, 49.1f, 131, 97);
        const GBuffer a = trace_gbuffer(native, sphere, cam), b = trace_gbuffer(eight, sphere, cam);
        const auto same = [&](const auto& x, const auto& y) {
            return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
        };
        EXPECT_TRUE(same(a.mask, b.mask) && same(a.triangle, b.triangle) &&
                    same(a.barycentric, b.barycentric) && same(a.depth, b.depth))
            << "view " << k;
        EXPECT_TRUE(same(a.position, b.position) && same(a.normal, b.normal) && same(a.tangent, b.tangent) &&
                    same(a.handedness, b.handedness))
            << "view " << k;
        EXPECT_TRUE(same(a.uv, b.uv) && same(a.duv_dx, b.duv_dx) && same(a.duv_dy, b.duv_dy)) << "view " << k;
        std::size_t hits = 0;
        for (float m : a.mask) hits += m > 0.f;
        EXPECT_GT(hits, a.pixel_count() / 4);
    }
}

TEST(Trace, EmptyImageIsAnError) {
    const TriangleMesh quad = make_quad(1.f);
    const EmbreeScene scene(quad);
    Camera cam = Camera::orbit(0, 0, 2, 49.1f, 16, 16);
    cam.width = 0;
    EXPECT_THROW(trace_gbuffer(scene, quad, cam), Error);
}
