#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/mesh/mesh_io.h>

#include <cstdint>
#include <cstring>
#include <fstream>

#include "common/test_paths.h"

using namespace tdf;

namespace {

std::string write_file(const std::string& name, const std::string& bytes) {
    const std::string path = test::scratch_dir() + "/" + name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

// Appends `value` as `T` in the given byte order.
template <typename T>
void put(std::string& out, T value, bool big_endian) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (big_endian)
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    out.append(bytes, sizeof(T));
}

// A unit quad (one polygon) with float colours and s/t UVs, in binary of either byte order.
std::string binary_quad(bool big_endian) {
    std::string out =
        std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
        " 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "property float red\nproperty float green\nproperty float blue\nproperty float s\nproperty float t\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const float v[4][8] = {{0, 0, 0, 1, 0, 0, 0, 0},
                           {1, 0, 0, 0, 1, 0, 1, 0},
                           {1, 1, 0, 0, 0, 1, 1, 1},
                           {0, 1, 0, 0.5f, 0.5f, 0.5f, 0, 1}};
    for (const auto& row : v)
        for (const float x : row) put(out, x, big_endian);
    put(out, std::uint8_t(4), big_endian);
    for (int i = 0; i < 4; ++i) put(out, std::int32_t(i), big_endian);
    return out;
}

void expect_quad(const TriangleMesh& mesh) {
    ASSERT_EQ(mesh.positions.size(), 4u);
    ASSERT_EQ(mesh.triangles.size(), 2u);  // fanned polygon
    EXPECT_EQ(mesh.triangles[1].x, 0);
    EXPECT_EQ(mesh.triangles[1].z, 3);
    ASSERT_TRUE(mesh.has_colors());
    EXPECT_NEAR(mesh.colors[1].y, 1.0f, 1e-6f);
    EXPECT_NEAR(mesh.colors[3].x, 0.5f, 1e-2f);
    ASSERT_TRUE(mesh.has_uvs());
    const Vec2f uv = mesh.uvs[std::size_t(mesh.uv_triangles[0].z)];
    EXPECT_FLOAT_EQ(uv.x, 1.0f);
    EXPECT_FLOAT_EQ(uv.y, 1.0f);
    EXPECT_NEAR(mesh.normals[0].z, 1.0f, 1e-6f);
}

}  // namespace

TEST(PlyIo, AsciiWithUcharColoursAndUvs) {
    const std::string path =
        write_file("quad_ascii.ply",
                   "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                   "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                   "property float u\nproperty float v\nelement face 1\n"
                   "property list uchar uint vertex_indices\nend_header\n"
                   "0 0 0 255 0 0 0 0\n1 0 0 0 255 0 1 0\n1 1 0 0 0 255 1 1\n0 1 0 128 128 128 0 1\n"
                   "4 0 1 2 3\n");
    expect_quad(load_ply(path));
}

TEST(PlyIo, BinaryLittleAndBigEndianWithFloatColours) {
    expect_quad(load_ply(write_file("quad_le.ply", binary_quad(false))));
    expect_quad(load_mesh(write_file("quad_be.ply", binary_quad(true))));
}

TEST(PlyIo, PerCornerTexcoordListsAndSkippedElements) {
    const std::string path =
        write_file("tri_texcoord.ply",
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                   "property double z\nproperty int flags\nelement face 1\n"
                   "property list uchar int vertex_index\nproperty list uchar float texcoord\n"
                   "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
                   "0 0 0 7\n1 0 0 7\n0 1 0 7\n3 0 1 2 6 0.1 0.2 0.9 0.2 0.1 0.8\n0 1\n");
    const TriangleMesh mesh = load_ply(path);
    ASSERT_EQ(mesh.triangles.size(), 1u);
    EXPECT_FALSE(mesh.has_colors());
    ASSERT_TRUE(mesh.has_uvs());
    EXPECT_FLOAT_EQ(mesh.uvs[std::size_t(mesh.uv_triangles[0].z)].y, 0.8f);
}

TEST(PlyIo, BadInputNamesFileAndProblem) {
    const auto expect_error =
        [](const std::string& name, const std::string& text, const std::string& needle) {
            const std::string path = write_file(name, text);
            try {
                load_ply(path);
                ADD_FAILURE() << name << " accepted";
            } catch (const Error& e) {
                const std::string message = e.what();
                EXPECT_NE(message.find(name), std::string::npos) << message;
                EXPECT_NE(message.find(needle), std::string::npos) << message;
            }
        };
    const std::string header =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    expect_error("not_ply.ply", "solid cube\n", "not a PLY file");
    expect_error("no_end.ply", "ply\nformat ascii 1.0\n", "end_header");
    expect_error("bad_type.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
                 "unknown PLY type");
    expect_error("truncated.ply", header + "0 0 0\n1 0 0\n", "truncated");
    expect_error("bad_index.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "uses vertex 7");
    expect_error("not_number.ply", header + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n", "not a number");
    expect_error("no_faces.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "property float z\nend_header\n0 0 0\n",
                 "no face element");
    expect_error("huge_count.ply",
                 "ply\nformat binary_little_endian 1.0\nelement vertex 99999999999\nend_header\n",
                 "declares 99999999999 items");
    expect_error("truncated_bin.ply", binary_quad(false).substr(0, 300), "truncated");
}
