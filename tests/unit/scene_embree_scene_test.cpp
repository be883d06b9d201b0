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

TEST(EmbreeScene, DeviceErrorsBecomeTdfErrors) {
    const TriangleMesh quad = make_quad();
    EmbreeScene scene(quad);
    // An invalid call on the scene's device: the callback records it, throw_if_error reports it.
    RTCGeometry bad = rtcNewGeometry(scene.device(), RTCGeometryType(12345));
    if (bad) rtcReleaseGeometry(bad);
    try {
        scene.throw_if_error("testing");
        ADD_FAILURE() << "no error reported";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("Embree error"), std::string::npos) << message;
        EXPECT_NE(message.find("while testing"), std::string::npos) << message;
    }
}
