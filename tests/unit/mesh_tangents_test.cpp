// Tangent frames across UV seams: a seam across which the UV layout only moves (a band's
// u = 0 / u = 1 cut) shares one frame on both sides, and a seam between charts turned against
// each other keeps one frame per side.
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>

#include "common/cone_band.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace tdf;

namespace {

constexpr int kSegments = 8;

// The band's cut at u = 0 / 1 is a translation seam; `turn_first_chart` gives segment 0 a chart of
// its own at u = 2, turned a quarter round.
TriangleMesh make_band(bool turn_first_chart) {
    return test::make_cone_band(kSegments, 1.0f / float(kSegments), 1.0f, 1.0f, 0.5f, turn_first_chart, {2.0f, 0.0f});
}

// The tangents of the corners of position `position` in the faces that have it.
std::vector<Vec3f> corner_tangents(const TriangleMesh& mesh, int position) {
    std::vector<Vec3f> out;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k)
            if (mesh.triangles[f][k] == position) {
                const Vec4f t = mesh.tangents[std::size_t(mesh.tangent_triangles[f][k])];
                out.push_back({t.x, t.y, t.z});
            }
    return out;
}

}  // namespace

TEST(MeshTangents, TranslationSeamSharesOneFrame) {
    const TriangleMesh band = make_band(false);
    // Position 0 lies on the cut: its corners have u = 0 (segment 0) and u = 1 (segment 7).
    const std::vector<Vec3f> tangents = corner_tangents(band, 0);
    ASSERT_GE(tangents.size(), 2u);
    // Both sides average all the faces around the vertex, so they hold one frame, and the band
    // being symmetric under turns about y, it is the frame of every other vertex of its ring
    // turned there (vertex 2 turned back by its angle).
    const float phi = 2.0f * kPi * 2.0f / float(kSegments);
    const std::vector<Vec3f> interior = corner_tangents(band, 2);
    ASSERT_FALSE(interior.empty());
    const Vec3f i = interior.front();
    const Vec3f turned{i.x * std::cos(phi) - i.z * std::sin(phi), i.y, i.x * std::sin(phi) + i.z * std::cos(phi)};
    for (const Vec3f& t : tangents) {
        EXPECT_NEAR(t.x, turned.x, 1e-5f);
        EXPECT_NEAR(t.y, turned.y, 1e-5f);
        EXPECT_NEAR(t.z, turned.z, 1e-5f);
    }
}

TEST(MeshTangents, TurnedChartsKeepTheirOwnFrames) {
    const TriangleMesh band = make_band(true);
    // Position 1 joins segment 0 (turned a quarter: its u runs along the band's height) and
    // segment 1: the two frames stay about a quarter turn apart (80 degrees on the cone's slant)
    // instead of sharing one frame.
    const std::vector<Vec3f> tangents = corner_tangents(band, 1);
    ASSERT_GE(tangents.size(), 2u);
    float smallest = 1.0f;
    for (const Vec3f& a : tangents)
        for (const Vec3f& b : tangents) smallest = std::min(smallest, std::fabs(dot(a, b)));
    EXPECT_LT(smallest, 0.3f);
}
