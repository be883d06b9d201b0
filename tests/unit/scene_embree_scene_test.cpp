#include <tdf/core/error.h>
#include <tdf/scene/embree_scene.h>
#include <tdf/scene/procedural_mesh.h>

#include <gtest/gtest.h>

using namespace tdf;

TEST(EmbreeScene, BuildsFromAMesh) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 32, 16);
    EmbreeScene scene(sphere);
    EXPECT_EQ(scene.triangle_count(), sphere.triangles.size());
    EXPECT_NE(scene.handle(), nullptr);
    EXPECT_NO_THROW(scene.throw_if_error("testing"));
}

TEST(EmbreeScene, EmptyMeshIsAnError) {
    TriangleMesh empty;
    empty.source_path = "empty.obj";
    try {
        EmbreeScene scene(empty);
        ADD_FAILURE() << "accepted an empty mesh";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("empty.obj"), std::string::npos) << e.what();
    }
}
