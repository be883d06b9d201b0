#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/render/antialias.h>
#include <tdf/render/raster.h>
#include <tdf/render/renderer.h>
#include <tdf/render/trace.h>
#include <tdf/scene/procedural_mesh.h>

#include <cmath>

using namespace tdf;

namespace {

// A plane of n x n quads (2 n^2 triangles) spanning [-h, h]^2 at z = 0, with UVs.
TriangleMesh make_grid(int n, float h) {
    TriangleMesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const float u = float(i) / float(n), v = float(j) / float(n);
            m.positions.push_back({-h + 2 * h * u, -h + 2 * h * v, 0.f});
            m.normals.push_back({0, 0, 1});
            m.uvs.push_back({u, v});
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            m.triangles.push_back({a, b, d});
            m.triangles.push_back({a, d, c});
        }
    m.uv_triangles = m.triangles;
    return m;
}

}  // namespace

TEST(Raster, QuadFacingTheCameraMatchesTheRayTracer) {
    const TriangleMesh quad = make_quad(1.f);
    const EmbreeScene scene(quad);
    const Camera cam = Camera::orbit(0, 0, 2, 90, 64, 64);
    GBuffer r;
    raster_gbuffer(quad, cam, r);
    const GBuffer t = trace_gbuffer(scene, quad, cam);
    float covered = 0;
    for (float m : r.mask) covered += m;
    EXPECT_EQ(covered, 32.f * 32.f);
    double max_uv = 0, max_duv = 0, max_pos = 0, max_depth = 0;
    for (std::size_t i = 0; i < r.pixel_count(); ++i) {
        ASSERT_EQ(r.mask[i], t.mask[i]) << i;
        if (!r.mask[i]) {
            EXPECT_EQ(r.triangle[i], -1);
            continue;
        }
        max_uv = std::max(
            {max_uv, double(std::fabs(r.uv[i].x - t.uv[i].x)), double(std::fabs(r.uv[i].y - t.uv[i].y))});
        max_duv = std::max({max_duv,
                            double(std::fabs(r.duv_dx[i].x - t.duv_dx[i].x)),
                            double(std::fabs(r.duv_dy[i].y - t.duv_dy[i].y))});
        max_pos = std::max(max_pos, double(length(r.position[i] - t.position[i])));
        max_depth = std::max(max_depth, double(std::fabs(r.depth[i] - t.depth[i])));
    }
    EXPECT_LT(max_uv, 1e-6);
    EXPECT_LT(max_duv, 1e-7);
    EXPECT_LT(max_pos, 2e-6);
    EXPECT_LT(max_depth, 2e-6);
}

TEST(Raster, OutputHasNvdiffrastLayout) {
    // One triangle; rast = (u, v, z/w, id + 1) with p = u p0 + v p1 + (1 - u - v) p2.
    TriangleMesh m = make_quad(1.f);
    const Camera cam = Camera::orbit(0, 0, 2, 90, 64, 64);
    const std::vector<Vec4f> clip = clip_positions(m, cam);
    RasterBuffer rb;
    rasterize(clip, m.triangles, 64, 64, rb);
    int checked = 0;
    for (int y = 0; y < 64; y += 3)
        for (int x = 0; x < 64; x += 3) {
            const Vec4f r = rb.rast[rb.index(x, y)];
            if (r.w == 0.f) {
                EXPECT_EQ(r.x, 0.f);
                continue;
            }
            const int t = int(r.w) - 1;
            const Vec3i tri = m.triangles[std::size_t(t)];
            // Screen position of the barycentric point (affine here: the quad faces the camera).
            const Vec3f p = m.positions[std::size_t(tri.x)] * r.x + m.positions[std::size_t(tri.y)] * r.y +
                            m.positions[std::size_t(tri.z)] * (1.f - r.x - r.y);
            EXPECT_NEAR(p.x, (float(x) + 0.5f) / 16.f - 2.f, 1e-5f);
            EXPECT_NEAR(p.y, 2.f - (float(y) + 0.5f) / 16.f, 1e-5f);  // row 0 = top (upright)
            // z/w of a plane at distance 2 with near 0.01, far 100.
            const float n = 0.01f, f = 100.f, zc = -2.f;
            const float z_ndc = (-(f + n) / (f - n) * zc - 2 * f * n / (f - n)) / -zc;
            EXPECT_NEAR(r.z, z_ndc, 1e-6f);
            ++checked;
        }
    EXPECT_GT(checked, 50);
}

TEST(Raster, SharedEdgesThroughPixelCentresAreWatertight) {
    // A 16 x 16 grid over [-1, 1]^2 seen with an orthographic 64 px window of the same size: every
    // vertex and the diagonals pass exactly through pixel centres or pixel corners. Each centre
    // must be covered (no gaps), and the depth test must not matter (coplanar, ties by index).
    const TriangleMesh grid = make_grid(16, 1.f);
    Camera cam = Camera::look_at({0, 0, 1}, {0, 0, 0}, Camera::Kind::Orthographic, 64, 64);
    cam.half_extent = 1.f;
    RasterBuffer rb;
    rasterize(clip_positions(grid, cam), grid.triangles, 64, 64, rb);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) ASSERT_GE(rb.triangle(rb.index(x, y)), 0) << x << "," << y;
    // With the window shifted by half a pixel the grid lines pass through pixel centres; still
    // no gaps, and each centre on a vertical edge belongs to the triangle on its right (left edge).
    cam.position = {1.f / 64.f, 1.f / 64.f, 1};
    rasterize(clip_positions(grid, cam), grid.triangles, 64, 64, rb);
    for (int y = 1; y < 63; ++y)
        for (int x = 1; x < 63; ++x) ASSERT_GE(rb.triangle(rb.index(x, y)), 0) << x << "," << y;
}

TEST(Raster, PlanarNearPlaneClipsAndTrianglesBehindTheCameraAreInvisible) {
    // A large floor through the camera: parts behind the camera and nearer than the near plane
    // must be background, the rest must match the ray tracer's planar clipping.
    const TriangleMesh grid = make_grid(8, 4.f);
    const EmbreeScene scene(grid);
    Camera cam = Camera::look_at({0.3f, 0.2f, 0.05f}, {0.3f, 2.f, -0.5f}, Camera::Kind::Perspective, 48, 48);
    GBuffer r;
    raster_gbuffer(grid, cam, r);
    const GBuffer t = trace_gbuffer(scene, grid, cam);
    int agree = 0, both = 0;
    for (std::size_t i = 0; i < r.pixel_count(); ++i) {
        agree += r.mask[i] == t.mask[i];
        both += r.mask[i] > 0;
        if (r.mask[i] > 0) {
            EXPECT_GE(r.depth[i], cam.near_plane * 0.999f);
        }
    }
    EXPECT_GT(both, 0);
    EXPECT_GE(agree, int(r.pixel_count()) - 48);  // at most the pixels along the clipped edge differ
}

TEST(Raster, SphereMatchesTheRayTracerAwayFromEdges) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 64, 32);
    const EmbreeScene scene(sphere);
    const Camera cam = Camera::orbit(-20, 30, 3, 49.1f, 128, 128);
    GBuffer r;
    raster_gbuffer(sphere, cam, r);
    const GBuffer t = trace_gbuffer(scene, sphere, cam);
    int same_triangle = 0, hits = 0, mask_diff = 0;
    double max_b = 0, max_lod_ratio = 0;
    for (std::size_t i = 0; i < r.pixel_count(); ++i) {
        mask_diff += r.mask[i] != t.mask[i];
        if (!r.mask[i] || !t.mask[i]) continue;
        ++hits;
        if (r.triangle[i] != t.triangle[i]) continue;
        ++same_triangle;
        max_b = std::max({max_b,
                          double(std::fabs(r.barycentric[i].x - t.barycentric[i].x)),
                          double(std::fabs(r.barycentric[i].y - t.barycentric[i].y))});
        const double jr = std::hypot(r.duv_dx[i].x, r.duv_dx[i].y) + std::hypot(r.duv_dy[i].x, r.duv_dy[i].y);
        const double jt = std::hypot(t.duv_dx[i].x, t.duv_dx[i].y) + std::hypot(t.duv_dy[i].x, t.duv_dy[i].y);
        if (jt > 0) max_lod_ratio = std::max(max_lod_ratio, std::fabs(jr / jt - 1));
    }
    EXPECT_LE(mask_diff, 8);                     // silhouette pixels only
    EXPECT_GE(same_triangle, hits - hits / 50);  // triangle edges only
    // Both are float32 results of ill-conditioned problems on triangles seen edge-on near the
    // silhouette (Embree's ray/triangle test, the rasterizer's float clip positions).
    EXPECT_LT(max_b, 1e-3);
    EXPECT_LT(max_lod_ratio, 1e-3);  // analytic derivatives = ray differentials
}

TEST(Raster, DerivativesMatchFiniteDifferencesOfTheBarycentrics) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 16, 8);
    const Camera cam = Camera::orbit(10, -40, 2.2f, 60, 256, 256);
    const std::vector<Vec4f> clip = clip_positions(sphere, cam);
    RasterBuffer rb;
    rasterize(clip, sphere.triangles, 256, 256, rb);
    int checked = 0;
    for (int y = 20; y < 230; y += 5)
        for (int x = 20; x < 230; x += 5) {
            const std::size_t i = rb.index(x, y), rx = rb.index(x + 1, y), ry = rb.index(x, y + 1);
            const std::size_t lx = rb.index(x - 1, y), uy = rb.index(x, y - 1);
            const int t = rb.triangle(i);
            if (t < 0 || rb.triangle(rx) != t || rb.triangle(ry) != t || rb.triangle(lx) != t ||
                rb.triangle(uy) != t)
                continue;
            // Central differences: second-order accurate.
            const float du_dx = 0.5f * (rb.rast[rx].x - rb.rast[lx].x),
                        dv_dy = 0.5f * (rb.rast[ry].y - rb.rast[uy].y);
            const float du_dy = 0.5f * (rb.rast[ry].x - rb.rast[uy].x),
                        dv_dx = 0.5f * (rb.rast[rx].y - rb.rast[lx].y);
            const Vec4f db = rb.rast_db[i];
            const float tol =
                0.02f * (std::fabs(db.x) + std::fabs(db.y) + std::fabs(db.z) + std::fabs(db.w)) + 1e-6f;
            EXPECT_NEAR(du_dx, db.x, tol);
            EXPECT_NEAR(du_dy, db.y, tol);
            EXPECT_NEAR(dv_dx, db.z, tol);
            EXPECT_NEAR(dv_dy, db.w, tol);
            ++checked;
        }
    EXPECT_GT(checked, 100);
}

TEST(Raster, BitIdenticalForAnyThreadCount) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 96, 48);
    const Camera cam = Camera::orbit(-15, 20, 2.5f, 49.1f, 200, 150);
    const std::vector<Vec4f> clip = clip_positions(sphere, cam);
    RasterBuffer one, two;
    {
        ThreadLimit limit(1);
        rasterize(clip, sphere.triangles, 200, 150, one);
    }
    {
        ThreadLimit limit(2);
        rasterize(clip, sphere.triangles, 200, 150, two);
    }
    ASSERT_EQ(one.rast.size(), two.rast.size());
    for (std::size_t i = 0; i < one.rast.size(); ++i)
        for (int k = 0; k < 4; ++k) {
            ASSERT_EQ(one.rast[i][k], two.rast[i][k]) << i;
            ASSERT_EQ(one.rast_db[i][k], two.rast_db[i][k]) << i;
        }
}

TEST(Raster, BadIndicesAreAnError) {
    RasterBuffer rb;
    EXPECT_THROW(rasterize({{0, 0, 0, 1}}, {{0, 0, 1}}, 8, 8, rb), Error);
    EXPECT_THROW(rasterize({}, {}, 0, 8, rb), Error);
}

TEST(Antialias, StraightSilhouetteGivesExactAreaCoverage) {
    // A quad whose right edge lies at pixel x = 40.3 (vertical) and top edge at row 20.8: the
    // antialiased coverage of the pixels just outside / inside the edges is the covered area.
    TriangleMesh m = make_quad(1.f);
    Camera cam = Camera::look_at({0, 0, 1}, {0, 0, 0}, Camera::Kind::Orthographic, 64, 64);
    cam.half_extent = 2.f;  // 16 px per unit; quad spans 32 px
    // Shift the camera so the quad's right edge (x = +1) falls at pixel coordinate 40.3 and its top
    // edge (y = +1, row 0 = top) at row 15.8.
    cam.position = {(32.f + 16.f - 40.3f) / 16.f, (32.f - 16.f - 15.8f) / -16.f, 1.f};
    const std::vector<Vec4f> clip = clip_positions(m, cam);
    RasterBuffer rb;
    rasterize(clip, m.triangles, 64, 64, rb);
    std::vector<int> tri(rb.rast.size());
    std::vector<float> depth(rb.rast.size());
    Image coverage(64, 64, 1);
    for (std::size_t i = 0; i < tri.size(); ++i) {
        tri[i] = rb.triangle(i);
        depth[i] = rb.rast[i].z;
        coverage.data()[i] = tri[i] >= 0 ? 1.f : 0.f;
    }
    // Edge at 40.3: pixel 39 (centre 39.5) covered, pixel 40 (centre 40.5) not.
    ASSERT_EQ(coverage.at(39, 30, 0), 1.f);
    ASSERT_EQ(coverage.at(40, 30, 0), 0.f);
    const EdgeTopology topology(m.triangles, m.positions.size());
    AntialiasPlan plan;
    plan.analyze(64, 64, tri.data(), depth.data(), clip, m.triangles, topology);
    EXPECT_GT(plan.blended_pairs(), 0u);
    Image aa = coverage;
    plan.apply(aa);
    EXPECT_NEAR(aa.at(40, 30, 0), 0.3f, 1e-4f);  // [40, 41] is 0.3 covered
    EXPECT_NEAR(aa.at(39, 30, 0), 1.f, 1e-6f);
    // Top edge at row 15.8: row 15 (centre 15.5) not covered, gets 0.2; row 16 stays 1.
    EXPECT_NEAR(aa.at(30, 15, 0), 0.2f, 1e-4f);
    EXPECT_NEAR(aa.at(30, 16, 0), 1.f, 1e-6f);
    // Interior edges (the quad's diagonal) are not silhouettes: the interior is untouched.
    for (int y = 17; y < 45; ++y)
        for (int x = 25; x < 39; ++x) ASSERT_EQ(aa.at(x, y, 0), 1.f) << x << "," << y;
}

TEST(Antialias, BitIdenticalForAnyThreadCount) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 48, 24);
    const Camera cam = Camera::orbit(-15, 20, 2.5f, 49.1f, 160, 120);
    const std::vector<Vec4f> clip = clip_positions(sphere, cam);
    RasterBuffer rb;
    rasterize(clip, sphere.triangles, 160, 120, rb);
    std::vector<int> tri(rb.rast.size());
    std::vector<float> depth(rb.rast.size());
    Image img(160, 120, 3);
    for (std::size_t i = 0; i < tri.size(); ++i) {
        tri[i] = rb.triangle(i);
        depth[i] = rb.rast[i].z;
        for (int k = 0; k < 3; ++k)
            img.data()[3 * i + std::size_t(k)] = tri[i] >= 0 ? float((tri[i] * (k + 3)) % 17) / 17.f : 1.f;
    }
    const EdgeTopology topology(sphere.triangles, sphere.positions.size());
    Image one = img, two = img;
    {
        ThreadLimit limit(1);
        AntialiasPlan plan;
        plan.analyze(160, 120, tri.data(), depth.data(), clip, sphere.triangles, topology);
        plan.apply(one);
    }
    {
        ThreadLimit limit(2);
        AntialiasPlan plan;
        plan.analyze(160, 120, tri.data(), depth.data(), clip, sphere.triangles, topology);
        plan.apply(two);
    }
    EXPECT_EQ(one.values(), two.values());
    EXPECT_NE(one.values(), img.values());  // the silhouette changed something
}

namespace {

// A textured sphere scene shared by the renderer-level tests.
struct TexturedSphere {
    TriangleMesh mesh = make_uv_sphere(1.f, 64, 32);
    EmbreeScene scene{mesh};
    MipTexture albedo, tactile;
    SurfaceMaterial material;
    TexturedSphere() {
        Image a(128, 128, 3), t(128, 128, 3);
        for (int y = 0; y < 128; ++y)
            for (int x = 0; x < 128; ++x) {
                const float s = std::sin(float(x) * 0.3f), c = std::cos(float(y) * 0.2f);
                a.at(x, y, 0) = 0.5f + 0.4f * s;
                a.at(x, y, 1) = 0.5f + 0.4f * c;
                a.at(x, y, 2) = 0.3f;
                const Vec3f n = safe_normalize({0.4f * s, 0.4f * c, 1.f});
                for (int k = 0; k < 3; ++k) t.at(x, y, k) = n[k];
            }
        albedo = MipTexture(a);
        tactile = MipTexture(t);
        material.albedo_source = SurfaceMaterial::AlbedoSource::Texture;
        material.albedo = &albedo;
        material.tactile = &tactile;
    }
};

const std::vector<Pass> kTenPasses = {Pass::Albedo,
                                      Pass::Lambertian,
                                      Pass::Mask,
                                      Pass::Depth,
                                      Pass::Normal,
                                      Pass::Tangent,
                                      Pass::Uv,
                                      Pass::TactileNormal,
                                      Pass::ShadingNormal,
                                      Pass::ShadingNormalViewspace};

// PSNR (peak 1) of pass k between two frames over pixels whose 3x3 neighbourhood is covered in
// both (the eroded mask), and the number of such pixels.
double eroded_psnr(const Frame& a, const Frame& b, std::size_t k, std::size_t& count) {
    const Image& ia = a.images[k];
    const Image& ib = b.images[k];
    double sq = 0;
    count = 0;
    for (int y = 1; y + 1 < ia.height(); ++y)
        for (int x = 1; x + 1 < ia.width(); ++x) {
            bool inside = true;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                    inside = inside && a.coverage.at(x + dx, y + dy, 0) > 0.5f &&
                             b.coverage.at(x + dx, y + dy, 0) > 0.5f;
            if (!inside) continue;
            for (int c = 0; c < ia.channels(); ++c) {
                const double d = double(ia.at(x, y, c)) - double(ib.at(x, y, c));
                sq += d * d;
            }
            ++count;
        }
    const double mse = sq / double(std::max<std::size_t>(1, count * std::size_t(ia.channels())));
    return mse > 0 ? 10 * std::log10(1 / mse) : 999.0;
}

}  // namespace

TEST(RasterRenderer, AgreesWithTheRayRendererAwayFromSilhouettes) {
    const TexturedSphere s;
    const Camera cam = Camera::orbit(-20, 35, 3, 49.1f, 96, 96);
    const Light light{Light::Kind::Point, {1, 2, 3}, 0.5f};
    for (ShadingMode mode : {ShadingMode::Training, ShadingMode::Visualizer}) {
        RenderSettings ray_settings, raster_settings;
        ray_settings.shading = raster_settings.shading = mode;
        raster_settings.visibility = Visibility::Raster;
        const Frame ray = Renderer(s.mesh, s.scene, s.material, ray_settings).render(cam, light, kTenPasses);
        const Frame raster =
            Renderer(s.mesh, s.scene, s.material, raster_settings).render(cam, light, kTenPasses);
        for (std::size_t k = 0; k < kTenPasses.size(); ++k) {
            if (kTenPasses[k] == Pass::Depth) continue;  // not in [0, 1]; checked below
            std::size_t count = 0;
            const double psnr = eroded_psnr(ray, raster, k, count);
            EXPECT_GT(count, 2000u);
            EXPECT_GE(psnr, 45.0) << pass_name(kTenPasses[k]) << " " << shading_mode_name(mode);
        }
    }
}

TEST(RasterRenderer, AntialiasingChangesOnlySilhouettePixels) {
    const TexturedSphere s;
    const Camera cam = Camera::orbit(-20, 35, 3, 49.1f, 96, 96);
    const Light light{Light::Kind::Directional, {0, 0, 1}, 0.1f};
    for (Visibility vis : {Visibility::Raster, Visibility::Ray})
        for (ShadingMode mode : {ShadingMode::Training, ShadingMode::Visualizer}) {
            RenderSettings hard, soft;
            hard.shading = soft.shading = mode;
            hard.visibility = soft.visibility = vis;
            soft.antialias = true;
            const Frame h = Renderer(s.mesh, s.scene, s.material, hard).render(cam, light, kTenPasses);
            const Frame a = Renderer(s.mesh, s.scene, s.material, soft).render(cam, light, kTenPasses);
            int changed = 0;
            for (std::size_t k = 0; k < kTenPasses.size(); ++k) {
                const Image& ih = h.images[k];
                const Image& ia = a.images[k];
                const bool aa_pass =
                    mode == ShadingMode::Training
                        ? (kTenPasses[k] == Pass::Albedo || kTenPasses[k] == Pass::Lambertian ||
                           kTenPasses[k] == Pass::TactileNormal || kTenPasses[k] == Pass::ShadingNormal ||
                           kTenPasses[k] == Pass::ShadingNormalViewspace)
                        : (kTenPasses[k] == Pass::Albedo || kTenPasses[k] == Pass::Lambertian);
                for (int y = 1; y + 1 < ih.height(); ++y)
                    for (int x = 1; x + 1 < ih.width(); ++x)
                        for (int c = 0; c < ih.channels(); ++c) {
                            if (ih.at(x, y, c) == ia.at(x, y, c)) continue;
                            ASSERT_TRUE(aa_pass) << pass_name(kTenPasses[k]);
                            // Only next to a change of coverage.
                            bool edge = false;
                            for (int dy = -1; dy <= 1; ++dy)
                                for (int dx = -1; dx <= 1; ++dx)
                                    edge = edge || h.coverage.at(x + dx, y + dy, 0) != h.coverage.at(x, y, 0);
                            ASSERT_TRUE(edge) << pass_name(kTenPasses[k]) << " at " << x << "," << y;
                            ++changed;
                        }
            }
            EXPECT_GT(changed, 50) << visibility_name(vis) << " " << shading_mode_name(mode);
        }
}

TEST(RasterRenderer, BitIdenticalForAnyThreadCount) {
    const TexturedSphere s;
    RenderSettings settings;
    settings.visibility = Visibility::Raster;
    settings.antialias = true;
    const Renderer renderer(s.mesh, s.scene, s.material, settings);
    const Camera cam = Camera::orbit(-10, 40, 3, 49.1f, 77, 61);
    const Light light{Light::Kind::Point, {1, 2, 3}, 0.5f};
    Frame one, two;
    {
        ThreadLimit limit(1);
        one = renderer.render_ssaa(cam, 1.37f, light, kTenPasses);
    }
    {
        ThreadLimit limit(2);
        two = renderer.render_ssaa(cam, 1.37f, light, kTenPasses);
    }
    for (std::size_t k = 0; k < kTenPasses.size(); ++k)
        EXPECT_EQ(one.images[k].values(), two.images[k].values());
}
