#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "common/test_paths.h"

using namespace tdf;

namespace {
std::string write_file(const std::string& name, const std::string& text) {
    const std::string path = test::scratch_dir() + "/" + name;
    std::ofstream(path) << text;
    return path;
}
}  // namespace

TEST(ObjIo, PolygonsNegativeIndicesAndVertexColours) {
    const std::string path = write_file("quad.obj",
                                        "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\n"
                                        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                        "f -4/-4 -3/-3 -2/-2 -1/-1\n");
    const TriangleMesh mesh = load_obj(path);
    ASSERT_EQ(mesh.triangles.size(), 2u);
    EXPECT_EQ(mesh.triangles[1].z, 3);
    ASSERT_TRUE(mesh.has_colors());
    EXPECT_FLOAT_EQ(mesh.colors[1].y, 1.0f);
    // Flat quad facing +Z: normals +Z, tangent +X (dP/du), right-handed (w = +1).
    EXPECT_NEAR(mesh.normals[0].z, 1.0f, 1e-6f);
    const Vec4f t = mesh.tangents[std::size_t(mesh.tangent_triangles[0].x)];
    EXPECT_NEAR(t.x, 1.0f, 1e-6f);
    EXPECT_FLOAT_EQ(t.w, 1.0f);
}

TEST(ObjIo, MirroredChartGetsNegativeHandedness) {
    // Same quad with u mirrored: dP/du = -X and N x T = -Y but v still increases along +Y.
    const std::string path = write_file("mirrored.obj",
                                        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                        "vt 1 0\nvt 0 0\nvt 0 1\nvt 1 1\nf 1/1 2/2 3/3 4/4\n");
    const TriangleMesh mesh = load_obj(path);
    const Vec4f t = mesh.tangents[std::size_t(mesh.tangent_triangles[0].x)];
    EXPECT_NEAR(t.x, -1.0f, 1e-6f);
    EXPECT_FLOAT_EQ(t.w, -1.0f);
    MeshLoadOptions reference;
    reference.tangent_mode = TangentMode::Reference;
    EXPECT_FLOAT_EQ(load_obj(path, reference).tangents[0].w, 1.0f);
}

TEST(ObjIo, BadInputNamesFileAndLine) {
    const auto expect_error = [](const std::string& name, const std::string& text, const std::string& needle) {
        const std::string path = write_file(name, text);
        try {
            load_obj(path);
            ADD_FAILURE() << name << " accepted";
        } catch (const Error& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(name), std::string::npos) << msg;
            EXPECT_NE(msg.find(needle), std::string::npos) << msg;
        }
    };
    expect_error("out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ":4: vertex index 4 is out of range");
    expect_error("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", ":2:");
    expect_error("empty.obj", "# nothing\n", "no vertices");
    expect_error("no_faces.obj", "v 0 0 0\n", "no faces");
    expect_error("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "zero area");
    expect_error("garbage.obj", "v 0 zero 0\n", "not a number");
    EXPECT_THROW(load_mesh(test::scratch_dir() + "/missing.obj"), Error);
}

TEST(ObjIo, LoadsRealMeshesWithTextures) {
    TDF_REQUIRE_SHARED_DATA("meshes/spot/spot_triangulated.obj");
    const TriangleMesh spot = load_obj(test::shared_data_dir() + "/meshes/spot/spot_triangulated.obj");
    EXPECT_EQ(spot.positions.size(), 2930u);
    EXPECT_EQ(spot.triangles.size(), 5856u);
    EXPECT_TRUE(spot.has_uvs());
    // The mug names a missing .mtl: loads with a warning, no albedo.
    const TriangleMesh mug = load_obj(test::shared_data_dir() + "/meshes/mug/mug.obj");
    EXPECT_EQ(mug.triangles.size(), 24544u);
    EXPECT_TRUE(mug.albedo.empty());
}

TEST(ObjIo, RecordsObjectsGroupsAndMaterialsPerFace) {
    const std::string path = write_file("groups.obj",
                                        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                        "o cactus\ng top\nusemtl green\nf 1 2 3\n"
                                        "usemtl brown\nusemtl red\nf 1 3 4\n"
                                        "o pot\ng\nusemtl clay\nf 1 2 3 4\n"
                                        "o cactus\ng top\nusemtl green\nf 2 3 4\n");
    const TriangleMesh mesh = load_obj(path);
    ASSERT_EQ(mesh.triangles.size(), 5u);
    ASSERT_EQ(mesh.face_groups.size(), 3u);  // "brown" has no faces; the last run reuses group 0
    EXPECT_EQ(mesh.face_group, (std::vector<int>{0, 1, 2, 2, 0}));
    EXPECT_EQ(mesh.face_groups[0].object, "cactus");
    EXPECT_EQ(mesh.face_groups[0].group, "top");
    EXPECT_EQ(mesh.face_groups[0].material, "green");
    EXPECT_EQ(mesh.face_groups[1].material, "red");
    EXPECT_EQ(mesh.face_groups[2].object, "pot");
    EXPECT_EQ(mesh.face_groups[2].group, "");
    EXPECT_EQ(mesh.face_groups[2].material, "clay");
    EXPECT_EQ(mesh.face_groups[2].gltf_node, -1);
    // No o/g/usemtl: no structure.
    EXPECT_TRUE(
        load_obj(write_file("plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).face_groups.empty());
}

TEST(ObjIo, ValidateRejectsInconsistentFaceGroups) {
    TriangleMesh mesh = load_obj(write_file("one.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\ng a\nf 1 2 3\n"));
    EXPECT_EQ(validate_mesh(mesh, "m"), 0u);
    mesh.face_group = {1};
    EXPECT_THROW(validate_mesh(mesh, "m"), Error);
    mesh.face_group = {0, 0};
    EXPECT_THROW(validate_mesh(mesh, "m"), Error);
}

TEST(ObjIo, NanTextureIsAnErrorNamingTheTexture) {
    // `atlas --bake-albedo` used to bake such texels as 0 without a word.
    Image texture(4, 4, 3, 0.5f);
    texture.at(1, 2, 0) = std::nanf("");
    const std::string exr = test::scratch_dir() + "/nan_texture.exr";
    write_exr(exr, texture);
    write_file("nan_texture.mtl", "newmtl m\nmap_Kd nan_texture.exr\n");
    const std::string path =
        write_file("nan_texture.obj",
                   "mtllib nan_texture.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                   "f 1/1 2/2 3/3\n");
    try {
        load_mesh(path);
        FAIL() << "a NaN texture was accepted";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("nan_texture.obj"), std::string::npos) << message;
        EXPECT_NE(message.find("nan_texture.exr"), std::string::npos) << message;
        EXPECT_NE(message.find("NaN"), std::string::npos) << message;
    }
    MeshLoadOptions no_textures;
    no_textures.load_textures = false;
    EXPECT_NO_THROW(load_mesh(path, no_textures));
}
