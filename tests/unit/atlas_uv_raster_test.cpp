#include <gtest/gtest.h>
#include <tdf/atlas/gutter.h>
#include <tdf/atlas/uv_raster.h>
#include <tdf/core/error.h>

#include <cmath>

using namespace tdf;

namespace {

// A unit quad in the XY plane whose UVs equal its positions, split along the diagonal.
TriangleMesh unit_quad() {
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    mesh.uv_triangles = mesh.triangles;
    return mesh;
}

}  // namespace

TEST(UvRaster, FullQuadCoversEveryTexelOnceWithExactBarycentrics) {
    const TriangleMesh mesh = unit_quad();
    const int size = 37;
    const UvRaster raster = rasterize_uv(mesh, size);
    ASSERT_EQ(raster.texel_count(), std::size_t(size * size));
    EXPECT_EQ(raster.covered_count(), std::size_t(size * size));
    for (int i = 0; i < size; ++i)
        for (int j = 0; j < size; ++j) {
            const std::size_t t = std::size_t(i * size + j);
            const int f = raster.triangle[t];
            ASSERT_GE(f, 0);
            const Vec3f w = raster.barycentric[t];
            EXPECT_NEAR(w.x + w.y + w.z, 1.0f, 1e-6f);
            // Interpolated position = UV = texel centre, with row 0 at the top (v near 1).
            Vec3f p{0, 0, 0};
            for (int k = 0; k < 3; ++k)
                p += mesh.positions[std::size_t(mesh.triangles[std::size_t(f)][k])] * w[k];
            EXPECT_NEAR(p.x, (j + 0.5f) / size, 1e-5f);
            EXPECT_NEAR(p.y, 1.0f - (i + 0.5f) / size, 1e-5f);
        }
}

TEST(UvRaster, SharedEdgeCentresBelongToExactlyOneTriangleForBothWindings) {
    // The diagonal of an even-sized raster passes exactly through texel centres.
    TriangleMesh mesh = unit_quad();
    for (int flip = 0; flip < 2; ++flip) {
        if (flip == 1)
            for (Vec3i& t : mesh.uv_triangles) std::swap(t.y, t.z);  // clockwise UVs
        mesh.triangles = mesh.uv_triangles;
        const UvRaster raster = rasterize_uv(mesh, 8);
        EXPECT_EQ(raster.covered_count(), 64u) << "flip " << flip;
        int on_diagonal_first = 0;
        for (int i = 0; i < 8; ++i) on_diagonal_first += raster.triangle[std::size_t(i * 8 + (7 - i))] == 0;
        EXPECT_TRUE(on_diagonal_first == 0 || on_diagonal_first == 8) << on_diagonal_first;
    }
}

TEST(UvRaster, InterpolatesVertexColoursAndSamplesBilinear) {
    TriangleMesh mesh = unit_quad();
    const std::vector<Vec3f> colours = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};  // = (u, v, 0)
    const UvRaster raster = rasterize_uv(mesh, 16);
    const Image image = interpolate_vertex_attribute(mesh, raster, colours);
    float rgb[3];
    // Bilinear lookup of a linear function is exact away from the clamped border.
    sample_bilinear(image, Vec2f{0.3f, 0.7f}, rgb);
    EXPECT_NEAR(rgb[0], 0.3f, 1e-5f);
    EXPECT_NEAR(rgb[1], 0.7f, 1e-5f);
}

TEST(UvRaster, PartialTexelsGoToTheTriangleTouchingThem) {
    // A triangle inside texel (row 1, column 2) of a 4x4 raster that misses the texel centre.
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    mesh.uvs = {{0.51f, 0.51f}, {0.6f, 0.51f}, {0.51f, 0.6f}};
    mesh.uv_triangles = mesh.triangles;
    UvRaster raster = rasterize_uv(mesh, 4);
    EXPECT_EQ(raster.covered_count(), 0u);
    add_partial_texels(mesh, raster);
    EXPECT_EQ(raster.covered_count(), 1u);
    const std::size_t t = 1 * 4 + 2;
    ASSERT_EQ(raster.triangle[t], 0);
    const Vec3f w = raster.barycentric[t];
    EXPECT_NEAR(w.x + w.y + w.z, 1.0f, 1e-6f);
    // The centre (u, v) = (0.625, 0.625) is nearest to the hypotenuse's midpoint.
    EXPECT_NEAR(w.y, 0.5f, 1e-5f);
    EXPECT_NEAR(w.z, 0.5f, 1e-5f);
}

TEST(UvRaster, RejectsMeshWithoutUvsAndBadSize) {
    TriangleMesh mesh = unit_quad();
    EXPECT_THROW(rasterize_uv(mesh, 0), Error);
    mesh.uv_triangles.clear();
    EXPECT_THROW(rasterize_uv(mesh, 16), Error);
}

TEST(Gutter, DilatesRingsFromCoveredNeighboursOnly) {
    const int w = 10, h = 4;
    Image image(w, h, 2, -1.0f);
    std::vector<int> coverage(std::size_t(w * h), -1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < 3; ++x) {
            coverage[std::size_t(y * w + x)] = 0;
            image.at(x, y, 0) = 0.25f;
            image.at(x, y, 1) = 0.75f;
        }
    dilate_gutter(image, coverage, 2);
    for (int y = 0; y < h; ++y) {
        for (int x = 3; x < 5; ++x) {
            EXPECT_FLOAT_EQ(image.at(x, y, 0), 0.25f) << x << "," << y;
            EXPECT_FLOAT_EQ(image.at(x, y, 1), 0.75f);
        }
        EXPECT_FLOAT_EQ(image.at(5, y, 0), -1.0f) << "third ring must stay empty";
    }
    dilate_gutter(image, coverage, 0);  // fill everything
    for (int y = 0; y < h; ++y) EXPECT_FLOAT_EQ(image.at(w - 1, y, 1), 0.75f);
}

TEST(Gutter, AveragesNeighboursAndRejectsMismatchedCoverage) {
    Image image(3, 1, 1, 0.0f);
    image.at(0, 0, 0) = 1.0f;
    image.at(2, 0, 0) = 3.0f;
    dilate_gutter(image, {0, -1, 0}, 1);
    EXPECT_FLOAT_EQ(image.at(1, 0, 0), 2.0f);
    EXPECT_THROW(dilate_gutter(image, {0, -1}, 1), Error);
}
