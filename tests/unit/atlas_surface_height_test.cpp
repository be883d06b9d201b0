// Heights on the surface (issue 24): texel steps from the UV Jacobian, seam links, and the
// least-squares move of texture-space heights onto the mesh (seams levelled, each texel at the
// map's or its own size).
#include <gtest/gtest.h>
#include <tdf/atlas/surface_height.h>
#include <tdf/atlas/surface_texels.h>
#include <tdf/atlas/uv_raster.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>

using namespace tdf;

namespace {

constexpr double kTwoPi = 6.28318530717958647692;

// An n x n grid over [0, width] x [0, 1] in the XY plane whose UVs span [u0, u1] x [v0, v1].
void add_grid(TriangleMesh& mesh, int n, float x0, float width, Vec2f uv0, Vec2f uv1) {
    const int base = int(mesh.positions.size()), uv_base = int(mesh.uvs.size());
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const float s = float(i) / float(n), t = float(j) / float(n);
            mesh.positions.push_back({x0 + s * width, t, 0.0f});
            mesh.uvs.push_back({uv0.x + s * (uv1.x - uv0.x), uv0.y + t * (uv1.y - uv0.y)});
        }
    const auto at = [&](int i, int j) { return j * (n + 1) + i; };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const Vec3i a{at(i, j), at(i + 1, j), at(i + 1, j + 1)}, b{at(i, j), at(i + 1, j + 1), at(i, j + 1)};
            mesh.triangles.push_back({base + a[0], base + a[1], base + a[2]});
            mesh.triangles.push_back({base + b[0], base + b[1], base + b[2]});
            mesh.uv_triangles.push_back({uv_base + a[0], uv_base + a[1], uv_base + a[2]});
            mesh.uv_triangles.push_back({uv_base + b[0], uv_base + b[1], uv_base + b[2]});
        }
}

// Two unit squares side by side (x in [0, 1] and [1, 2]) sharing the edge x = 1, each its own
// UV island: a seam down the middle of the surface.
TriangleMesh two_islands() {
    TriangleMesh mesh;
    add_grid(mesh, 4, 0.0f, 1.0f, {0.05f, 0.3f}, {0.45f, 0.7f});
    add_grid(mesh, 4, 1.0f, 1.0f, {0.55f, 0.3f}, {0.95f, 0.7f});
    // Weld the shared edge: the second grid's column 0 is the first grid's column 4.
    const int n = 4, offset = (n + 1) * (n + 1);
    for (auto& t : mesh.triangles)
        for (int k = 0; k < 3; ++k)
            if (t[k] >= offset && (t[k] - offset) % (n + 1) == 0) t[k] = (t[k] - offset) / (n + 1) * (n + 1) + n;
    return mesh;
}

double max_abs_difference(const Image& a, const Image& b, const SurfaceTexels& s) {
    double worst = 0;
    for (std::uint32_t t : s.texels) worst = std::max(worst, double(std::abs(a.data()[t] - b.data()[t])));
    return worst;
}

}  // namespace

TEST(SurfaceTexels, StepsFollowTheUvJacobian) {
    // A 2 x 1 rectangle mapped onto a square UV range: a column step is twice a row step.
    TriangleMesh mesh;
    add_grid(mesh, 3, 0.0f, 2.0f, {0.0f, 0.0f}, {1.0f, 1.0f});
    const int size = 32;
    const SurfaceTexels s = surface_texels(mesh, rasterize_uv(mesh, size));
    ASSERT_EQ(s.covered_count(), std::size_t(size * size));
    for (const TexelStep& d : s.step) {
        EXPECT_NEAR(d.along_x_t, 2.0f / size, 1e-6f);
        EXPECT_NEAR(d.along_y_t, 0.0f, 1e-6f);
        EXPECT_NEAR(d.along_y_b, -1.0f / size, 1e-6f);  // a row down is -v, and B points to +v
    }
    EXPECT_TRUE(s.seam_links.empty());
}

TEST(SurfaceTexels, SeamLinksJoinTheTwoIslandsAlongTheSharedEdge) {
    const TriangleMesh mesh = two_islands();
    const int size = 100;
    const SurfaceTexels s = surface_texels(mesh, rasterize_uv(mesh, size));
    // The shared edge is 0.4 UV units = 40 texels long on each side: about one link per texel.
    EXPECT_GE(s.seam_links.size(), std::size_t(38));
    EXPECT_LE(s.seam_links.size(), std::size_t(42));
    for (const auto& [a, b] : s.seam_links) {
        EXPECT_NE(s.chart[std::size_t(a)], s.chart[std::size_t(b)]);
        const int xa = int(s.texels[std::size_t(a)] % std::uint32_t(size)), xb = int(s.texels[std::size_t(b)] % std::uint32_t(size));
        EXPECT_NEAR(xa, 44, 1);  // the right edge of the left island (u = 0.45)
        EXPECT_NEAR(xb, 55, 1);  // the left edge of the right island (u = 0.55)
    }
}

TEST(SurfaceHeight, IsometricAtlasWithoutSeamsGivesTheHeightsBack) {
    TriangleMesh mesh;
    add_grid(mesh, 4, 0.0f, 1.0f, {0.0f, 0.0f}, {1.0f, 1.0f});
    const int size = 64;
    const SurfaceTexels s = surface_texels(mesh, rasterize_uv(mesh, size));
    Image texture(size, size, 1);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            texture.at(x, y, 0) = static_cast<float>(0.1 * std::sin(kTwoPi * x / 16.0) * std::cos(kTwoPi * y / 21.0) + 0.01 * x);
    double mean = 0;
    for (float v : texture.values()) mean += v;
    mean /= double(texture.pixel_count());
    for (float& v : texture.values()) v = float(v - mean);
    // 1 mesh unit = 64 mm: a texel is 1 mm on the surface and on the map.
    for (HeightMetric metric : {HeightMetric::Map, HeightMetric::Surface}) {
        SurfaceHeightStats stats;
        const Image out = heights_on_surface(texture, 1.0f, s, 64.0f, metric, &stats);
        EXPECT_LT(max_abs_difference(out, texture, s), 1e-4) << int(metric);
        EXPECT_LT(stats.relative_residual, 1e-4);
    }
}

TEST(SurfaceHeight, SurfaceTexelSizeTakesTheStretchIntoTheHeights) {
    // The rectangle is 2 units long on a square UV range: along x a texel spans twice the map's
    // mean texel. A relief that varies along x only is integrable at both sizes: with the
    // surface's texel size its slopes hold over twice the length, so its heights double.
    TriangleMesh mesh;
    add_grid(mesh, 4, 0.0f, 2.0f, {0.0f, 0.0f}, {1.0f, 1.0f});
    const int size = 64;
    const SurfaceTexels s = surface_texels(mesh, rasterize_uv(mesh, size));
    Image texture(size, size, 1);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) texture.at(x, y, 0) = static_cast<float>(2.0 * std::sin(kTwoPi * x / 16.0));
    const float mm_per_unit = 64.0f / std::sqrt(2.0f), texel_mm = 1.0f;  // the mean texel: sqrt(2 x 1) / 64 units
    const Image map = heights_on_surface(texture, texel_mm, s, mm_per_unit, HeightMetric::Map);
    const Image surface = heights_on_surface(texture, texel_mm, s, mm_per_unit, HeightMetric::Surface);
    const auto amplitude = [&](const Image& h) {
        const auto [lo, hi] = std::minmax_element(h.values().begin(), h.values().end());
        return 0.5 * double(*hi - *lo);
    };
    EXPECT_NEAR(amplitude(map), 2.0, 0.002);
    // Along x a texel is 2 / 64 units = 2 / sqrt(2) mm: sqrt(2) times the map's 1 mm.
    EXPECT_NEAR(amplitude(surface) / amplitude(map), std::sqrt(2.0), 0.01);
    // And its slopes per surface length are the map's: the consistency check at the surface's
    // texel size holds for normals made at the map's size with the same slopes.
    Image normals(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double slope = 0.5 * (texture.at((x + 1) % size, y, 0) - texture.at((x + size - 1) % size, y, 0)) / texel_mm;
            const double l = std::sqrt(slope * slope + 1);
            normals.at(x, y, 0) = float(-slope / l), normals.at(x, y, 1) = 0.0f, normals.at(x, y, 2) = float(1 / l);
        }
    EXPECT_GT(surface_height_consistency(surface, normals, s, mm_per_unit), 0.999);
    EXPECT_LT(surface_height_consistency(map, normals, s, mm_per_unit), 0.999);  // the stretch shows
}

TEST(SurfaceHeight, ChartsMeetLevelAcrossTheSeam) {
    // Texture-space integration leaves each island at its own level: here 0 and 1 mm.
    const TriangleMesh mesh = two_islands();
    const int size = 100;
    const SurfaceTexels s = surface_texels(mesh, rasterize_uv(mesh, size));
    Image texture(size, size, 1);
    for (std::size_t i = 0; i < s.covered_count(); ++i)
        texture.data()[s.texels[i]] = s.chart[i] == s.chart[0] ? 0.0f : 1.0f;
    const Image out = heights_on_surface(texture, 0.1f, s, 25.0f, HeightMetric::Map);
    double worst = 0;
    for (const auto& [a, b] : s.seam_links)
        worst = std::max(worst, double(std::abs(out.data()[s.texels[std::size_t(a)]] - out.data()[s.texels[std::size_t(b)]])));
    EXPECT_LT(worst, 1e-4);
    const auto [lo, hi] = std::minmax_element(out.values().begin(), out.values().end());
    EXPECT_LT(*hi - *lo, 1e-4f);  // one flat surface again, at zero mean
    EXPECT_NEAR(*lo, 0.0f, 1e-4f);
}

TEST(SurfaceHeight, SameResultOnOneAndTwoThreads) {
    const TriangleMesh mesh = two_islands();
    const int size = 128;
    const SurfaceTexels s = surface_texels(mesh, rasterize_uv(mesh, size));
    Image texture(size, size, 1);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) texture.at(x, y, 0) = static_cast<float>(std::sin(0.37 * x) * std::cos(0.21 * y) + 0.01 * x);
    Image one, two;
    {
        ThreadLimit limit(1);
        one = heights_on_surface(texture, 0.1f, s, 25.0f, HeightMetric::Surface);
    }
    {
        ThreadLimit limit(2);
        two = heights_on_surface(texture, 0.1f, s, 25.0f, HeightMetric::Surface);
    }
    EXPECT_EQ(one.values(), two.values());
}
