#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/mesh/mesh_writer.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <nlohmann/json.hpp>
#include <sstream>

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
    write_obj(path, mesh, ObjMaterial{"mat", "albedo.png", "normal.png", "", 0, 0});
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
    for (const char* name : {"POSITION", "NORMAL", "TANGENT", "TEXCOORD_0"})
        EXPECT_TRUE(attributes.contains(name)) << name;
    EXPECT_FALSE(attributes.contains("COLOR_0")) << "the albedo texture replaces the vertex colours";
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

namespace {

struct GlbFile {
    nlohmann::json json;
    std::string bin;
};
GlbFile read_glb(const std::string& path) {
    const std::string bytes = read_text_file(path);
    std::uint32_t json_length = 0, bin_length = 0;
    std::memcpy(&json_length, bytes.data() + 12, 4);
    std::memcpy(&bin_length, bytes.data() + 20 + json_length, 4);
    return {nlohmann::json::parse(bytes.substr(20, json_length)),
            bytes.substr(20 + json_length + 8, bin_length)};
}
std::string view_bytes(const GlbFile& glb, std::size_t view_index) {
    const auto& view = glb.json["bufferViews"][view_index];
    return glb.bin.substr(view["byteOffset"].get<std::size_t>(), view["byteLength"].get<std::size_t>());
}

// Two quads in world coordinates as a glTF loader leaves them: node "plain" (identity) and node
// "moved" whose matrix (scale 2, quarter turn about z, translation, optionally mirrored in x) the
// loader applied.
TriangleMesh two_node_mesh(bool mirror) {
    TriangleMesh mesh;
    const auto matrix = [mirror](Vec3f p) {  // world = M local
        const float sx = mirror ? -1.f : 1.f;
        return Vec3f{-2.f * p.y + 5.f, 2.f * sx * p.x + 1.f, 2.f * p.z - 3.f};
    };
    const Vec3f quad[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    for (const Vec3f& p : quad) mesh.positions.push_back(p);
    for (const Vec3f& p : quad) mesh.positions.push_back(matrix(p));
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    if (mirror)
        mesh.triangles[2] = {4, 6, 5}, mesh.triangles[3] = {4, 7, 6};  // the loader keeps CCW in world
    mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    mesh.uv_triangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 2}, {0, 2, 3}};
    if (mirror) mesh.uv_triangles[2] = {0, 2, 1}, mesh.uv_triangles[3] = {0, 3, 2};
    finish_loaded_mesh(mesh, "two nodes", {});
    FaceGroup plain, moved;
    plain.object = "plain";
    plain.group = "plain_mesh";
    plain.gltf_node = 0;
    plain.gltf_mesh = 0;
    plain.gltf_primitive = 0;
    moved.object = "moved";
    moved.group = "moved_mesh";
    moved.gltf_node = 3;
    moved.gltf_mesh = 1;
    moved.gltf_primitive = 0;
    const float sx = mirror ? -1.f : 1.f;
    moved.world_from_node = {0, 2 * sx, 0, 0, -2, 0, 0, 0, 0, 0, 2, 0, 5, 1, -3, 1};
    mesh.face_groups = {plain, moved};
    mesh.face_group = {0, 0, 1, 1};
    return mesh;
}

}  // namespace

TEST(MeshWriter, ObjWritesTheRendererNormalsAndTheInputGroups) {
    TriangleMesh mesh = coloured_quad();
    mesh.face_groups = {FaceGroup{"body", "front", "cloth"}, FaceGroup{"body", "back", "cloth"}};
    mesh.face_group = {0, 1};
    const std::string path = test::scratch_dir() + "/writer_normals.obj";
    write_obj(path, mesh, ObjMaterial{"mat", "albedo.png", "normal.png", "", 0, 0});
    const std::string text = read_text_file(path);
    std::vector<Vec3f> normals;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);)
        if (line.rfind("vn ", 0) == 0) {
            Vec3f n;
            std::istringstream(line.substr(3)) >> n.x >> n.y >> n.z;
            normals.push_back(n);
        }
    ASSERT_EQ(normals.size(), mesh.positions.size());
    for (std::size_t i = 0; i < normals.size(); ++i)
        EXPECT_LT(length(normals[i] - mesh.normals[i]), 1e-6f) << "vn " << i + 1;
    EXPECT_NE(text.find("f 1/1/1 2/2/2 3/3/3"), std::string::npos) << text;
    EXPECT_EQ(text.find("o body"), text.rfind("o body")) << "one `o` line for the one object";
    EXPECT_LT(text.find("g front"), text.find("g back"));
    // Our reader still reads it (and recomputes the same normals).
    MeshLoadOptions options;
    options.load_textures = false;
    const TriangleMesh loaded = load_obj(path, options);
    ASSERT_EQ(loaded.normals.size(), mesh.normals.size());
    EXPECT_LT(length(loaded.normals[3] - mesh.normals[3]), 1e-6f);
}

TEST(MeshWriter, GlbEmbedsTheGivenPngBytesAndLeavesVertexColoursToTheTexture) {
    const TriangleMesh mesh = coloured_quad();
    GlbMaps maps;
    maps.albedo_png = encode_png_bytes(Image(3, 2, 3, 0.3f), Quantize::Truncate);
    maps.normal_png = encode_png_bytes(Image(2, 2, 3, 0.5f), Quantize::Truncate);
    const std::string path = test::scratch_dir() + "/writer_bytes.glb";
    write_glb(path, mesh, maps);
    const GlbFile glb = read_glb(path);
    ASSERT_EQ(glb.json["images"].size(), 2u);
    EXPECT_EQ(view_bytes(glb, glb.json["images"][0]["bufferView"]), maps.albedo_png);
    EXPECT_EQ(view_bytes(glb, glb.json["images"][1]["bufferView"]), maps.normal_png);
    EXPECT_FALSE(glb.json["meshes"][0]["primitives"][0]["attributes"].contains("COLOR_0"))
        << "glTF would multiply the vertex colours into the texture";
    // The same PNG file write_png writes.
    const std::string file = test::scratch_dir() + "/writer_bytes_albedo.png";
    write_png(file, Image(3, 2, 3, 0.3f), 8, Quantize::Truncate);
    EXPECT_EQ(read_text_file(file), maps.albedo_png);
}

TEST(MeshWriter, GlbKeepsTheInputNodesAndWritesPositionsInNodeCoordinates) {
    for (const bool mirror : {false, true}) {
        SCOPED_TRACE(mirror ? "mirroring node matrix" : "rotation, scale, translation");
        const TriangleMesh mesh = two_node_mesh(mirror);
        const std::string path = test::scratch_dir() + "/writer_nodes.glb";
        write_glb(path, mesh);
        const GlbFile glb = read_glb(path);
        ASSERT_EQ(glb.json["nodes"].size(), 2u);
        ASSERT_EQ(glb.json["meshes"].size(), 2u);
        EXPECT_EQ(glb.json["nodes"][0]["name"], "plain");
        EXPECT_FALSE(glb.json["nodes"][0].contains("matrix"));
        EXPECT_EQ(glb.json["nodes"][1]["name"], "moved");
        EXPECT_EQ(glb.json["meshes"][1]["name"], "moved_mesh");
        ASSERT_TRUE(glb.json["nodes"][1].contains("matrix"));
        EXPECT_EQ(glb.json["nodes"][1]["matrix"][12].get<double>(), 5.0);
        // The moved node's mesh is the unit quad again in its own coordinates.
        const auto& position =
            glb.json["accessors"]
                    [glb.json["meshes"][1]["primitives"][0]["attributes"]["POSITION"].get<std::size_t>()];
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(position["min"][k].get<double>(), 0.0, 1e-6) << k;
            EXPECT_NEAR(position["max"][k].get<double>(), k < 2 ? 1.0 : 0.0, 1e-6) << k;
        }
        // Read back by our loader (which applies the matrices): the same surface, same winding.
        MeshLoadOptions options;
        options.load_textures = false;
        const TriangleMesh loaded = load_mesh(path, options);
        ASSERT_EQ(loaded.triangles.size(), mesh.triangles.size());
        for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
            const auto face_normal = [](const TriangleMesh& m, std::size_t face) {
                const Vec3i t = m.triangles[face];
                return normalize_or_zero(
                    cross(m.positions[std::size_t(t.y)] - m.positions[std::size_t(t.x)],
                          m.positions[std::size_t(t.z)] - m.positions[std::size_t(t.x)]));
            };
            EXPECT_LT(length(face_normal(loaded, f) - face_normal(mesh, f)), 1e-5f) << "face " << f;
            Vec3f a{0, 0, 0}, b{0, 0, 0};
            for (int k = 0; k < 3; ++k) {
                a += loaded.positions[std::size_t(loaded.triangles[f][k])];
                b += mesh.positions[std::size_t(mesh.triangles[f][k])];
            }
            EXPECT_LT(length(a - b), 1e-5f) << "face " << f;
        }
    }
}

// Issue 24: the height map and its scale travel with the asset. The MTL names it as
// `disp -mm base gain` (mesh units); the GLB embeds its very bytes as an image no texture
// uses, and names it with the scale under the material's extras (glTF core has no
// displacement), leaving the core textures as they were.
TEST(MeshWriter, HeightMapGoesToTheMtlAsDispAndToTheGlbExtras) {
    const TriangleMesh mesh = coloured_quad();
    ObjMaterial material;
    material.albedo_map = "q_albedo.png";
    material.normal_map = "q_normal.png";
    material.height_map = "q_height.png";
    material.height_base = -0.0125, material.height_gain = 0.05;
    const std::string obj = test::scratch_dir() + "/writer_height.obj";
    write_obj(obj, mesh, material);
    const std::string mtl = read_text_file(test::scratch_dir() + "/writer_height.mtl");
    EXPECT_NE(mtl.find("disp -mm -0.0125 0.05 q_height.png\n"), std::string::npos) << mtl;
    EXPECT_NE(mtl.find("map_Bump -bm 1 q_normal.png\n"), std::string::npos) << mtl;

    GlbMaps maps;
    maps.albedo_png = encode_png_bytes(Image(2, 2, 3, 0.3f), Quantize::Truncate);
    maps.normal_png = encode_png_bytes(Image(2, 2, 3, 0.5f), Quantize::Truncate);
    maps.height_png = "not really a png, but embedded byte for byte";
    maps.height_extras = {{"mm_per_unit", 25.0}, {"min_mm", -0.3}, {"max_mm", 0.9}};
    const std::string path = test::scratch_dir() + "/writer_height.glb";
    write_glb(path, mesh, maps);
    const GlbFile glb = read_glb(path);
    ASSERT_EQ(glb.json["images"].size(), 3u);
    ASSERT_EQ(glb.json["textures"].size(), 2u);  // the height is no core texture
    const auto& extras = glb.json["materials"][0]["extras"]["tdf_height"];
    ASSERT_TRUE(extras.is_object()) << glb.json["materials"][0].dump();
    EXPECT_EQ(extras["mm_per_unit"].get<double>(), 25.0);
    EXPECT_EQ(extras["max_mm"].get<double>(), 0.9);
    const std::size_t image = extras["image"].get<std::size_t>();
    EXPECT_EQ(view_bytes(glb, glb.json["images"][image]["bufferView"]), maps.height_png);
    EXPECT_EQ(glb.json["materials"][0]["normalTexture"]["index"].get<int>(), 1);
}

TEST(MeshWriter, OneMaterialAndPrimitivePerPartInObjAndGlb) {
    // scenes/four_part_sphere's mesh with its four bands as parts, numbered in another order
    // than the input's materials and named apart from them, so what comes back is the parts'.
    MeshLoadOptions options;
    options.load_textures = false;
    const TriangleMesh mesh = load_mesh(test::source_dir() + "/scenes/four_part_sphere/sphere.obj", options);
    const std::vector<std::string> bands = {"grain", "weave", "dimples", "ribs"};
    FaceMaterials parts;
    parts.names = {"part_grain", "part_weave", "part_dimples", "part_ribs"};
    std::map<std::string, std::size_t> faces_of;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const std::string band = mesh.face_groups[std::size_t(mesh.face_group[f])].material;
        const int k = int(std::find(bands.begin(), bands.end(), band) - bands.begin());
        ASSERT_LT(k, 4) << band;
        parts.face_material.push_back(k);
        ++faces_of[parts.names[std::size_t(k)]];
    }
    ObjMaterial material;
    material.albedo_map = "a.png";
    material.normal_map = "n.png";
    const std::string obj = test::scratch_dir() + "/writer_parts.obj", glb = test::scratch_dir() + "/writer_parts.glb";
    write_obj(obj, mesh, material, parts);
    write_glb(glb, mesh, GlbMaps{}, parts);

    // OBJ: faces in their order, each under its part's usemtl; every MTL material names both maps.
    const TriangleMesh from_obj = load_mesh(obj, options);
    ASSERT_EQ(from_obj.triangles.size(), mesh.triangles.size());
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        ASSERT_EQ(from_obj.face_groups[std::size_t(from_obj.face_group[f])].material,
                  parts.names[std::size_t(parts.face_material[f])]) << "face " << f;
    const std::string mtl = read_text_file(test::scratch_dir() + "/writer_parts.mtl");
    for (const std::string& name : parts.names) EXPECT_NE(mtl.find("newmtl " + name + "\n"), std::string::npos) << name;
    std::size_t normal_maps = 0;
    for (std::size_t at = mtl.find("norm n.png"); at != std::string::npos; at = mtl.find("norm n.png", at + 1)) ++normal_maps;
    EXPECT_EQ(normal_maps, 4u);

    // GLB: four materials named as the parts, one primitive per part, each on its material.
    const GlbFile file = read_glb(glb);
    ASSERT_EQ(file.json["materials"].size(), 4u);
    for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(file.json["materials"][k]["name"], parts.names[k]);
    ASSERT_EQ(file.json["meshes"].size(), 1u);
    const auto& primitives = file.json["meshes"][0]["primitives"];
    ASSERT_EQ(primitives.size(), 4u);
    std::set<int> used;
    for (const auto& p : primitives) used.insert(p["material"].get<int>());
    EXPECT_EQ(used.size(), 4u);
    const TriangleMesh from_glb = load_mesh(glb, options);
    std::map<std::string, std::size_t> glb_faces_of;
    for (std::size_t f = 0; f < from_glb.triangles.size(); ++f)
        ++glb_faces_of[from_glb.face_groups[std::size_t(from_glb.face_group[f])].material];
    EXPECT_EQ(glb_faces_of, faces_of);

    // A face count that does not match is refused in one line naming the file.
    parts.face_material.pop_back();
    try {
        write_glb(test::scratch_dir() + "/writer_parts_bad.glb", mesh, GlbMaps{}, parts);
        FAIL() << "accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("writer_parts_bad.glb"), std::string::npos) << e.what();
        EXPECT_FALSE(std::filesystem::exists(test::scratch_dir() + "/writer_parts_bad.glb"));
    }
}
