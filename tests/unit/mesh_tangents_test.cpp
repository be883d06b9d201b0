// Tangent frames across UV seams: a seam across which the UV layout only moves (a band's
// u = 0 / u = 1 cut) shares one frame on both sides, and a seam between charts turned against
// each other keeps one frame per side.
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace tdf;

namespace {

constexpr int kSegments = 8;

// An open cone band around y (radius 1 at y = 0, 0.5 at y = 1), u = s / kSegments around it (the
// column u = 1 duplicates u = 0), v = y. On a cone the faces' dP/du, horizontal chords, leave
// the tangent planes of the vertices at an angle, so a side that averages only its own faces
// turns its frame about the normal (on a cylinder the projection would hide that). With `turn_first_chart`, the faces of segment 0 get their
// own UVs, turned a quarter round inside their own square: a seam that is not a translation.
TriangleMesh make_band(bool turn_first_chart) {
    TriangleMesh mesh;
    mesh.source_path = "band";
    for (int ring = 0; ring < 2; ++ring)
        for (int s = 0; s < kSegments; ++s) {
            const float phi = 2.0f * kPi * float(s) / float(kSegments);
            const float radius = ring == 0 ? 1.0f : 0.5f;
            mesh.positions.push_back({radius * std::sin(phi), float(ring), radius * std::cos(phi)});
        }
    for (int ring = 0; ring < 2; ++ring)
        for (int s = 0; s <= kSegments; ++s) mesh.uvs.push_back({float(s) / float(kSegments), float(ring)});
    const auto p = [](int ring, int s) { return ring * kSegments + s % kSegments; };
    const auto t = [](int ring, int s) { return ring * (kSegments + 1) + s; };
    for (int s = 0; s < kSegments; ++s) {
        Vec3i t0{t(0, s), t(0, s + 1), t(1, s + 1)}, t1{t(0, s), t(1, s + 1), t(1, s)};
        if (s == 0 && turn_first_chart) {
            // Corners (0,0) (1,0) (1,1) (0,1) of the square become (1,0) (1,1) (0,1) (0,0).
            const int base = int(mesh.uvs.size());
            const float w = 1.0f / float(kSegments);
            for (Vec2f c : {Vec2f{w, 0}, Vec2f{w, 1}, Vec2f{0, 1}, Vec2f{0, 0}}) mesh.uvs.push_back({2.0f + c.x, c.y});
            t0 = {base, base + 1, base + 2};
            t1 = {base, base + 2, base + 3};
        }
        // Counter-clockwise seen from outside (u grows with phi, v with y).
        mesh.triangles.push_back({p(0, s), p(0, s + 1), p(1, s + 1)});
        mesh.uv_triangles.push_back(t0);
        mesh.triangles.push_back({p(0, s), p(1, s + 1), p(1, s)});
        mesh.uv_triangles.push_back(t1);
    }
    compute_normals(mesh);
    compute_tangents(mesh);
    return mesh;
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
