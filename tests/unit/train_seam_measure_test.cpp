// The seam measure of issue 10 goal 4: which triangle pairs are seams (MeshSeams) and how a
// jump across a seam is weighed against the steps beside it (SeamJump).
#include <tdf/render/gbuffer.h>
#include <tdf/scene/procedural_mesh.h>
#include <tdf/train/texture_fidelity.h>

#include <gtest/gtest.h>

using namespace tdf;

TEST(SeamMeasure, SphereHasOneMeridianSeamAndTwoPoleCones) {
    constexpr int kSegments = 12, kRings = 6;
    const TriangleMesh sphere = make_uv_sphere(1.0f, kSegments, kRings);
    const MeshSeams seams(sphere);
    // The u = 0 / 1 meridian: one edge per ring band. Each pole's fan: every other edge keeps the
    // ring corner's UV and moves the pole's (a cone).
    EXPECT_EQ(seams.seam_edges(), std::size_t(kRings));
    EXPECT_EQ(seams.cone_edges(), std::size_t(2 * (kSegments - 1)));
    // Faces 1 and 2 are the two triangles of segment 0's first quad: one chart.
    EXPECT_EQ(seams.between(1, 2), EdgeContinuity::Continuous);
    EXPECT_EQ(seams.between(3, 3), EdgeContinuity::Same);
}

namespace {

// Two triangles sharing the position edge (1, 2), with UVs shifted by one across it: a seam.
// Pixel row of 8: pixels 0-3 on triangle 0, 4-7 on triangle 1, same depth.
struct SeamRow {
    TriangleMesh mesh;
    GBuffer g;
    SeamRow() {
        mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {2, 0, 0}};
        mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
        mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {-1, 1}, {0, 1}};
        mesh.uv_triangles = {{0, 1, 2}, {3, 4, 5}};
        g.resize(8, 1);  // contents unspecified until written
        for (int x = 0; x < 8; ++x) {
            g.clear_pixel(std::size_t(x));
            g.mask[std::size_t(x)] = 1.0f;
            g.depth[std::size_t(x)] = 2.0f;
            g.triangle[std::size_t(x)] = x < 4 ? 0 : 1;
        }
    }
};

Image ramp(float seam_step) {
    Image image(8, 1, 1);
    for (int x = 0; x < 8; ++x) image.data()[x] = 0.1f * float(x) + (x >= 4 ? seam_step : 0.0f);
    return image;
}

}  // namespace

TEST(SeamMeasure, JumpIsWeighedAgainstTheStepsBesideIt) {
    const SeamRow row;
    const MeshSeams seams(row.mesh);
    ASSERT_EQ(seams.between(0, 1), EdgeContinuity::Seam);
    SeamJump smooth, stepped;
    smooth.add(row.g, ramp(0.0f), seams);
    stepped.add(row.g, ramp(0.5f), seams);
    ASSERT_EQ(smooth.seam_pairs, 1u);  // the pair (3, 4), with steps (1,2) (2,3) (4,5) (5,6) beside it
    EXPECT_NEAR(smooth.ratio(), 1.0, 1e-5);
    EXPECT_NEAR(stepped.ratio(), 6.0, 1e-4);  // (0.1 + 0.5) / 0.1
}

TEST(SeamMeasure, OcclusionEdgesAndContinuousEdgesAreNotSeams) {
    SeamRow row;
    row.mesh.uv_triangles = {{0, 1, 2}, {1, 3, 2}};  // triangle 1 continues triangle 0's UVs
    row.mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {2, 0}};
    const MeshSeams continuous(row.mesh);
    EXPECT_EQ(continuous.between(0, 1), EdgeContinuity::Continuous);
    SeamJump jumps;
    jumps.add(row.g, ramp(0.5f), continuous);
    EXPECT_EQ(jumps.seam_pairs, 0u);
    // The seam again, but the right half 10 % farther away: an occlusion edge counts nowhere.
    SeamRow occluded;
    for (int x = 4; x < 8; ++x) occluded.g.depth[std::size_t(x)] = 2.2f;
    SeamJump none;
    none.add(occluded.g, ramp(0.5f), MeshSeams(occluded.mesh));
    EXPECT_EQ(none.seam_pairs, 0u);
}

TEST(SeamMeasure, SeamsAlongCreasesAreNotCounted) {
    SeamRow row;
    // Fold triangle 1 up by 90 degrees about the shared edge (x = 1): a base meeting a side.
    row.mesh.positions[3] = {1, 0, 1};
    const MeshSeams folded(row.mesh);
    EXPECT_EQ(folded.between(0, 1), EdgeContinuity::Apart);
    EXPECT_EQ(folded.crease_edges(), 1u);
    EXPECT_EQ(MeshSeams(row.mesh, 100.0f).between(0, 1), EdgeContinuity::Seam);
}
