#include <tdf/core/error.h>
#include <tdf/mesh/mesh_io.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>

using namespace tdf;

namespace {

// A quad (4 vertices, 2 triangles) as glTF: positions, TEXCOORD_0, COLOR_0, uint16 indices.
struct QuadBuffer {
    std::vector<unsigned char> bytes;
    void append(const void* p, std::size_t n) {
        const auto* c = static_cast<const unsigned char*>(p);
        bytes.insert(bytes.end(), c, c + n);
    }
};

QuadBuffer quad_buffer(float nan_position = 0.f, std::uint16_t last_index = 3) {
    QuadBuffer b;
    const float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, nan_position, 1, 0};
    const float uv[8] = {0, 1, 1, 1, 1, 0, 0, 0};  // glTF v down: the bottom edge has v = 1
    const float col[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    const std::uint16_t idx[6] = {0, 1, 2, 0, 2, last_index};
    b.append(pos, sizeof pos);
    b.append(uv, sizeof uv);
    b.append(col, sizeof col);
    b.append(idx, sizeof idx);
    return b;
}

nlohmann::json quad_json(const std::string& buffer_uri, std::size_t buffer_size) {
    using nlohmann::json;
    json j;
    j["asset"] = {{"version", "2.0"}};
    json buffer = {{"byteLength", buffer_size}};
    if (!buffer_uri.empty()) buffer["uri"] = buffer_uri;
    j["buffers"] = json::array({buffer});
    j["bufferViews"] = json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
                                    {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 32}},
                                    {{"buffer", 0}, {"byteOffset", 80}, {"byteLength", 48}},
                                    {{"buffer", 0}, {"byteOffset", 128}, {"byteLength", 12}}});
    j["accessors"] = json::array({{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
                                  {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
                                  {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
                                  {{"bufferView", 3}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}});
    j["meshes"] = json::array(
        {{{"primitives", json::array({{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}, {"COLOR_0", 2}}},
                                       {"indices", 3}}})}}});
    // The mesh node sits under a parent translated by (0, 0, 5) and scaled by 2.
    j["nodes"] = json::array({{{"children", json::array({1})}, {"translation", {0, 0, 5}}},
                              {{"mesh", 0}, {"scale", {2, 2, 2}}}});
    j["scenes"] = json::array({{{"nodes", json::array({0})}}});
    j["scene"] = 0;
    return j;
}

std::string write_gltf(const std::string& name, const QuadBuffer& buffer) {
    const std::string dir = test::scratch_dir();
    std::ofstream(dir + "/" + name + ".bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(buffer.bytes.data()), std::streamsize(buffer.bytes.size()));
    const std::string path = dir + "/" + name + ".gltf";
    std::ofstream(path) << quad_json(name + ".bin", buffer.bytes.size()).dump();
    return path;
}

std::string write_glb(const std::string& name, const QuadBuffer& buffer) {
    std::string json = quad_json("", buffer.bytes.size()).dump();
    while (json.size() % 4) json += ' ';
    std::vector<unsigned char> bin = buffer.bytes;
    while (bin.size() % 4) bin.push_back(0);
    const std::uint32_t total = 12 + 8 + std::uint32_t(json.size()) + 8 + std::uint32_t(bin.size());
    const std::string path = test::scratch_dir() + "/" + name + ".glb";
    std::ofstream out(path, std::ios::binary);
    auto u32 = [&](std::uint32_t v) { out.write(reinterpret_cast<const char*>(&v), 4); };
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(total);
    u32(std::uint32_t(json.size()));
    u32(0x4E4F534A);  // "JSON"
    out.write(json.data(), std::streamsize(json.size()));
    u32(std::uint32_t(bin.size()));
    u32(0x004E4942);  // "BIN\0"
    out.write(reinterpret_cast<const char*>(bin.data()), std::streamsize(bin.size()));
    return path;
}

void check_quad(const TriangleMesh& mesh) {
    ASSERT_EQ(mesh.triangles.size(), 2u);
    ASSERT_EQ(mesh.positions.size(), 4u);
    // Node transforms: scale 2 then translate z by 5.
    EXPECT_FLOAT_EQ(mesh.positions[2].x, 2.f);
    EXPECT_FLOAT_EQ(mesh.positions[2].y, 2.f);
    EXPECT_FLOAT_EQ(mesh.positions[2].z, 5.f);
    // glTF v down -> tdf v up: vertex 0 (bottom-left) gets v = 0.
    ASSERT_TRUE(mesh.has_uvs());
    EXPECT_FLOAT_EQ(mesh.uvs[std::size_t(mesh.uv_triangles[0].x)].y, 0.f);
    EXPECT_FLOAT_EQ(mesh.uvs[std::size_t(mesh.uv_triangles[0].z)].y, 1.f);
    ASSERT_TRUE(mesh.has_colors());
    EXPECT_FLOAT_EQ(mesh.colors[1].y, 1.f);
    EXPECT_NEAR(mesh.normals[0].z, 1.f, 1e-6f);
    EXPECT_NEAR(mesh.tangents[std::size_t(mesh.tangent_triangles[0].x)].x, 1.f, 1e-6f);
}

}  // namespace

TEST(GltfIo, ReadsGltfAndGlbWithNodeTransforms) {
    check_quad(load_mesh(write_gltf("quad", quad_buffer())));
    check_quad(load_mesh(write_glb("quad", quad_buffer())));
}

TEST(GltfIo, BadInputIsOneLineNamingTheFile) {
    const auto expect_error = [](const std::string& path, const std::string& needle) {
        try {
            load_mesh(path);
            ADD_FAILURE() << path << " accepted";
        } catch (const Error& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(std::filesystem::path(path).filename().string()), std::string::npos) << msg;
            EXPECT_NE(msg.find(needle), std::string::npos) << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        }
    };
    expect_error(write_gltf("nan", quad_buffer(std::nanf(""))), "non-finite");
    expect_error(write_gltf("bad_index", quad_buffer(0.f, 9)), "out of range");
    // Truncated binary buffer.
    QuadBuffer short_buffer = quad_buffer();
    const std::string truncated = write_gltf("truncated", short_buffer);
    std::filesystem::resize_file(test::scratch_dir() + "/truncated.bin", 60);
    expect_error(truncated, "truncated");
    // Truncated .glb and garbage JSON.
    const std::string glb = write_glb("cut", quad_buffer());
    std::filesystem::resize_file(glb, 40);
    expect_error(glb, "cannot read glTF");
    const std::string garbage = test::scratch_dir() + "/garbage.gltf";
    std::ofstream(garbage) << "{ not json";
    expect_error(garbage, "cannot read glTF");
    EXPECT_THROW(load_mesh(test::scratch_dir() + "/missing.gltf"), Error);
}

TEST(GltfIo, LoadsTheAvocadoWithItsBaseColourTexture) {
    TDF_REQUIRE_SHARED_DATA("meshes/avocado_gltf/Avocado.gltf");
    const TriangleMesh mesh = load_mesh(test::shared_data_dir() + "/meshes/avocado_gltf/Avocado.gltf");
    EXPECT_EQ(mesh.triangles.size(), 682u);
    EXPECT_TRUE(mesh.has_uvs());
    EXPECT_EQ(mesh.albedo.width(), 2048);
    EXPECT_EQ(mesh.albedo.height(), 2048);
    EXPECT_GE(mesh.albedo.channels(), 3);
    // About 4.3 x 6.3 x 2.8 cm (shared/data README).
    const Bounds3 b = compute_bounds(mesh);
    EXPECT_NEAR(b.extent().y, 0.063f, 0.003f);
    EXPECT_LT(b.extent().x, b.extent().y);
    // Welding: fewer positions than UV vertices (glTF splits vertices at UV seams).
    EXPECT_LT(mesh.positions.size(), mesh.uvs.size());
    // One node, mesh and primitive with material "2256_Avocado_d": one group for every face.
    ASSERT_EQ(mesh.face_groups.size(), 1u);
    EXPECT_EQ(mesh.face_groups[0].material, "2256_Avocado_d");
    EXPECT_EQ(mesh.face_groups[0].group, "Avocado");
    EXPECT_EQ(mesh.face_group, std::vector<int>(682, 0));
}

TEST(GltfIo, RecordsNodeMeshPrimitiveAndMaterialPerFace) {
    // Two primitives (materials "skin", "sole") of a mesh "shoe" under the translated/scaled node.
    const QuadBuffer buffer = quad_buffer();
    nlohmann::json j = quad_json("groups.bin", buffer.bytes.size());
    nlohmann::json prim = j["meshes"][0]["primitives"][0];
    prim["material"] = 0;
    nlohmann::json second = prim;
    second["material"] = 1;
    j["meshes"][0]["primitives"] = nlohmann::json::array({prim, second});
    j["meshes"][0]["name"] = "shoe";
    j["nodes"][1]["name"] = "left";
    j["materials"] = nlohmann::json::array({{{"name", "skin"}}, {{"name", "sole"}}});
    const std::string dir = test::scratch_dir();
    std::ofstream(dir + "/groups.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(buffer.bytes.data()), std::streamsize(buffer.bytes.size()));
    std::ofstream(dir + "/groups.gltf") << j.dump();
    const TriangleMesh mesh = load_mesh(dir + "/groups.gltf");
    ASSERT_EQ(mesh.triangles.size(), 4u);
    ASSERT_EQ(mesh.face_groups.size(), 2u);
    EXPECT_EQ(mesh.face_group, (std::vector<int>{0, 0, 1, 1}));
    for (int g = 0; g < 2; ++g) {
        const FaceGroup& group = mesh.face_groups[std::size_t(g)];
        EXPECT_EQ(group.object, "left");
        EXPECT_EQ(group.group, "shoe");
        EXPECT_EQ(group.material, g == 0 ? "skin" : "sole");
        EXPECT_EQ(group.gltf_node, 1);
        EXPECT_EQ(group.gltf_mesh, 0);
        EXPECT_EQ(group.gltf_primitive, g);
        EXPECT_EQ(group.gltf_material, g);
        // World matrix, column-major: scale 2 then translate z by 5.
        EXPECT_DOUBLE_EQ(group.world_from_node[0], 2.0);
        EXPECT_DOUBLE_EQ(group.world_from_node[10], 2.0);
        EXPECT_DOUBLE_EQ(group.world_from_node[14], 5.0);
        EXPECT_DOUBLE_EQ(group.world_from_node[15], 1.0);
    }
}

namespace {
// The quad with one accessor edited.
std::string write_edited_gltf(const std::string& name, int accessor, const nlohmann::json& changes) {
    const QuadBuffer buffer = quad_buffer();
    const std::string dir = test::scratch_dir();
    std::ofstream(dir + "/" + name + ".bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(buffer.bytes.data()), std::streamsize(buffer.bytes.size()));
    nlohmann::json j = quad_json(name + ".bin", buffer.bytes.size());
    j["accessors"][std::size_t(accessor)].update(changes);
    const std::string path = dir + "/" + name + ".gltf";
    std::ofstream(path) << j.dump();
    return path;
}
std::string gltf_error(const std::string& path) {
    try {
        load_mesh(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}
}  // namespace

TEST(GltfIo, PositionMustBeFloat) {
    // glTF 2.0: POSITION is FLOAT; UNSIGNED_BYTE positions were read as small integers.
    const std::string ubyte = write_edited_gltf("pos_ubyte", 0, {{"componentType", 5121}});
    const std::string message = gltf_error(ubyte);
    EXPECT_NE(message.find("pos_ubyte.gltf"), std::string::npos) << message;
    EXPECT_NE(message.find("POSITION has component type UNSIGNED_BYTE, expected FLOAT"), std::string::npos)
        << message;
    const std::string normalized =
        gltf_error(write_edited_gltf("pos_ushort", 0, {{"componentType", 5123}, {"normalized", true}}));
    EXPECT_NE(normalized.find("POSITION has component type UNSIGNED_SHORT (normalized)"), std::string::npos)
        << normalized;
    // TEXCOORD_0 as non-normalized bytes is invalid too; normalized bytes are allowed.
    EXPECT_NE(gltf_error(write_edited_gltf("uv_ubyte", 1, {{"componentType", 5121}})).find("TEXCOORD_0"),
              std::string::npos);
}

TEST(GltfIo, HugeAccessorCountIsRefusedBeforeAllocating) {
    for (const std::int64_t count : {std::int64_t(2147483647), std::int64_t(1) << 40}) {
        const std::string path = write_edited_gltf("count_" + std::to_string(count), 0, {{"count", count}});
        const std::string message = gltf_error(path);
        EXPECT_NE(message.find(std::filesystem::path(path).filename().string()), std::string::npos)
            << message;
        EXPECT_NE(message.find("POSITION"), std::string::npos) << message;
    }
    // A byte stride beyond the buffer cannot wrap around either.
    const std::string stride = gltf_error(write_edited_gltf("offset", 0, {{"byteOffset", 4294967295ll}}));
    EXPECT_NE(stride.find("offset.gltf"), std::string::npos) << stride;
}
