#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/mesh/mesh_writer.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/test_paths.h"

using namespace tdf;

namespace {

TriangleMesh coloured_quad() {
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5f}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.uvs = {{0.1f, 0.2f}, {0.9f, 0.2f}, {0.9f, 0.8f}, {0.1f, 0.8f}};
    mesh.uv_triangles = mesh.triangles;
    mesh.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.5f, 0.25f, 0.125f}};
    finish_loaded_mesh(mesh, "quad", {});
    return mesh;
}

}  // namespace

TEST(MeshWriter, ObjRoundTripKeepsGeometryUvsColoursAndNamesBothMaps) {
    const TriangleMesh mesh = coloured_quad();
    const std::string path = test::scratch_dir() + "/writer_quad.obj";
    write_obj(path, mesh, ObjMaterial{"mat", "albedo.png", "normal.png"});
    MeshLoadOptions options;
    options.load_textures = false;
    const TriangleMesh loaded = load_obj(path, options);
    ASSERT_EQ(loaded.positions.size(), mesh.positions.size());
    ASSERT_EQ(loaded.triangles.size(), mesh.triangles.size());
    ASSERT_TRUE(loaded.has_uvs());
    ASSERT_TRUE(loaded.has_colors());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        EXPECT_FLOAT_EQ(loaded.positions[i].z, mesh.positions[i].z);
        EXPECT_NEAR(loaded.colors[i].z, mesh.colors[i].z, 1e-6f);
    }
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            EXPECT_EQ(loaded.triangles[f][k], mesh.triangles[f][k]);
            const Vec2f a = loaded.uvs[std::size_t(loaded.uv_triangles[f][k])];
            const Vec2f b = mesh.uvs[std::size_t(mesh.uv_triangles[f][k])];
            EXPECT_FLOAT_EQ(a.x, b.x);
            EXPECT_FLOAT_EQ(a.y, b.y);
        }
    const std::string mtl = read_text_file(test::scratch_dir() + "/writer_quad.mtl");
    EXPECT_NE(mtl.find("map_Kd albedo.png"), std::string::npos) << mtl;
    EXPECT_NE(mtl.find("norm normal.png"), std::string::npos) << mtl;
    EXPECT_NE(mtl.find("map_Bump -bm 1 normal.png"), std::string::npos) << mtl;
}

TEST(MeshWriter, GlbHasValidChunksAttributesAndEmbeddedMaps) {
    const TriangleMesh mesh = coloured_quad();
    const Image albedo(4, 4, 3, 0.5f), normal(4, 4, 3, 0.5f);
    const std::string path = test::scratch_dir() + "/writer_quad.glb";
    write_glb(path, mesh, &albedo, &normal);
    const std::string bytes = read_text_file(path);
    ASSERT_GE(bytes.size(), 28u);
    std::uint32_t header[5];
    std::memcpy(header, bytes.data(), sizeof(header));
    EXPECT_EQ(header[0], 0x46546C67u);
    EXPECT_EQ(header[1], 2u);
    EXPECT_EQ(header[2], bytes.size());
    EXPECT_EQ(header[4], 0x4E4F534Au);
    const auto json = nlohmann::json::parse(bytes.substr(20, header[3]));
    const auto& attributes = json["meshes"][0]["primitives"][0]["attributes"];
    for (const char* name : {"POSITION", "NORMAL", "TANGENT", "TEXCOORD_0", "COLOR_0"})
        EXPECT_TRUE(attributes.contains(name)) << name;
    EXPECT_TRUE(json["materials"][0]["pbrMetallicRoughness"].contains("baseColorTexture"));
    EXPECT_TRUE(json["materials"][0].contains("normalTexture"));
    EXPECT_EQ(json["images"].size(), 2u);
    // TEXCOORD_0 is v-down: read the first vertex's texcoord back from the BIN chunk.
    const std::size_t bin_start = 20 + header[3] + 8;
    const auto& accessor = json["accessors"][attributes["TEXCOORD_0"].get<std::size_t>()];
    const std::size_t offset = json["bufferViews"][accessor["bufferView"].get<std::size_t>()]["byteOffset"];
    float uv[2];
    std::memcpy(uv, bytes.data() + bin_start + offset, sizeof(uv));
    EXPECT_FLOAT_EQ(uv[0], 0.1f);
    EXPECT_FLOAT_EQ(uv[1], 1.0f - 0.2f);
    EXPECT_FALSE(std::filesystem::exists(path + ".texture.png"));
}

TEST(MeshWriter, EmptyMeshIsAnError) {
    EXPECT_THROW(write_obj(test::scratch_dir() + "/empty.obj", TriangleMesh{}), Error);
}
