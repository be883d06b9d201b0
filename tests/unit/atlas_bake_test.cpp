#include <gtest/gtest.h>
#include <tdf/atlas/bake.h>
#include <tdf/atlas/uv_atlas.h>
#include <tdf/core/error.h>
#include <tdf/core/rng.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "common/test_paths.h"

using namespace tdf;

namespace {

struct Comparison {
    double psnr = 0;
    double max_error = 0;
};

// Compares expected(f, b) with actual(f, b) (RGB) at `count` random surface points (uniform face,
// uniform barycentrics), as PSNR over [0, 1] values.
Comparison compare_at_random_points(const TriangleMesh& mesh, int count,
                                    const std::function<void(std::size_t, Vec3f, float*)>& expected,
                                    const std::function<void(std::size_t, Vec3f, float*)>& actual) {
    Rng rng(7);
    double squared = 0;
    Comparison c;
    for (int i = 0; i < count; ++i) {
        const auto f = std::size_t(rng.uniform_int(0, int(mesh.triangles.size())));
        const float r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
        const Vec3f b{1 - r1, r1 * (1 - r2), r1 * r2};
        float e[3], a[3];
        expected(f, b, e);
        actual(f, b, a);
        for (int k = 0; k < 3; ++k) {
            const double d = double(e[k]) - double(a[k]);
            squared += d * d;
            c.max_error = std::max(c.max_error, std::abs(d));
        }
    }
    c.psnr = 10.0 * std::log10(1.0 / std::max(squared / (3.0 * count), 1e-20));
    return c;
}

// The barycentric interpolation of the vertex colours at (face f, weights b): the reference.
void vertex_colour_at(const TriangleMesh& mesh, std::size_t f, Vec3f b, float* out) {
    const Vec3i& t = mesh.triangles[f];
    const Vec3f v = mesh.colors[std::size_t(t.x)] * b.x + mesh.colors[std::size_t(t.y)] * b.y +
                    mesh.colors[std::size_t(t.z)] * b.z;
    out[0] = v.x;
    out[1] = v.y;
    out[2] = v.z;
}

Vec2f uv_at(const TriangleMesh& mesh, std::size_t f, Vec3f b) {
    const Vec3i& t = mesh.uv_triangles[f];
    return mesh.uvs[std::size_t(t.x)] * b.x + mesh.uvs[std::size_t(t.y)] * b.y +
           mesh.uvs[std::size_t(t.z)] * b.z;
}

// Spot with per-vertex colours sampled from its own texture (the data has no vertex colours).
TriangleMesh coloured_spot() {
    TriangleMesh mesh = load_mesh(test::shared_data_dir() + "/meshes/spot/spot_triangulated.obj");
    // Spot's OBJ names no material; its texture sits beside it (data README).
    if (mesh.albedo.empty())
        mesh.albedo = read_image(test::shared_data_dir() + "/meshes/spot/spot_texture.png");
    mesh.colors.assign(mesh.positions.size(), Vec3f{});
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            float rgb[4];
            sample_bilinear(mesh.albedo, mesh.uvs[std::size_t(mesh.uv_triangles[f][k])], rgb);
            mesh.colors[std::size_t(mesh.triangles[f][k])] = {rgb[0], rgb[1], rgb[2]};
        }
    return mesh;
}

}  // namespace

TEST(Bake, LinearVertexColoursOnAPlaneBakeExactly) {
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.colors = {{0, 0, 0.5f}, {1, 0, 0.5f}, {1, 1, 0.5f}, {0, 1, 0.5f}};
    AtlasOptions options;
    options.size = 64;
    const TriangleMesh atlas = build_atlas(mesh, options);
    const Image baked = bake_vertex_colors(atlas, options.size);
    const Comparison c = compare_at_random_points(
        atlas,
        2000,
        [&](std::size_t f, Vec3f b, float* out) { vertex_colour_at(atlas, f, b, out); },
        [&](std::size_t f, Vec3f b, float* out) { sample_bilinear(baked, uv_at(atlas, f, b), out); });
    std::printf("plane bake: PSNR %.1f dB, max error %.2g\n", c.psnr, c.max_error);
    // Bilinear reconstruction of a linear function is exact inside the chart; only lookups
    // within a texel of the border blend in the gutter's averaged (not extrapolated) values.
    EXPECT_GT(c.psnr, 60.0);
}

TEST(Bake, VertexColourBakeMatchesBarycentricInterpolationOnSpot) {
    TDF_REQUIRE_SHARED_DATA("meshes/spot/spot_triangulated.obj");
    const TriangleMesh mesh = coloured_spot();
    AtlasOptions options;
    options.reunwrap = true;
    const TriangleMesh atlas = build_atlas(mesh, options);
    const Image baked = bake_vertex_colors(atlas, options.size);
    ASSERT_EQ(baked.width(), 1024);
    EXPECT_TRUE(baked.all_finite());
    const Comparison c = compare_at_random_points(
        atlas,
        20000,
        [&](std::size_t f, Vec3f b, float* out) { vertex_colour_at(mesh, f, b, out); },
        [&](std::size_t f, Vec3f b, float* out) { sample_bilinear(baked, uv_at(atlas, f, b), out); });
    std::printf("spot vertex-colour bake vs direct interpolation: PSNR %.1f dB, max error %.3f\n",
                c.psnr,
                c.max_error);
    EXPECT_GT(c.psnr, 50.0);  // measured 56.6 dB
}

TEST(Bake, RebakedTextureMatchesTheOriginalAtTheSameSurfacePoints) {
    TDF_REQUIRE_SHARED_DATA("meshes/spot/spot_triangulated.obj");
    const TriangleMesh mesh = load_mesh(test::shared_data_dir() + "/meshes/spot/spot_triangulated.obj");
    const Image texture = read_image(test::shared_data_dir() + "/meshes/spot/spot_texture.png");
    AtlasOptions options;
    options.reunwrap = true;
    const TriangleMesh atlas = build_atlas(mesh, options);
    const Image rebaked = rebake_texture(mesh, texture, atlas, options.size);
    EXPECT_EQ(rebaked.channels(), texture.channels());
    const Comparison c = compare_at_random_points(
        atlas,
        20000,
        [&](std::size_t f, Vec3f b, float* out) {
            float v[4];
            sample_bilinear(texture, uv_at(mesh, f, b), v);
            std::copy(v, v + 3, out);
        },
        [&](std::size_t f, Vec3f b, float* out) {
            float v[4];
            sample_bilinear(rebaked, uv_at(atlas, f, b), v);
            std::copy(v, v + 3, out);
        });
    std::printf("spot texture re-bake vs original: PSNR %.1f dB, max error %.3f\n", c.psnr, c.max_error);
    EXPECT_GT(c.psnr, 44.0);  // measured 48.9 dB
}

TEST(Bake, BadInputIsAnError) {
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    mesh.uvs = {{0, 0}, {1, 0}, {0, 1}};
    mesh.uv_triangles = mesh.triangles;
    EXPECT_THROW(bake_vertex_colors(mesh, 16), Error);  // no colours
    TriangleMesh other = mesh;
    other.triangles = {{0, 2, 1}};
    EXPECT_THROW(rebake_texture(mesh, Image(4, 4, 3), other, 16), Error);  // different faces
    EXPECT_THROW(rebake_texture(mesh, Image(), mesh, 16), Error);          // no texture
}
