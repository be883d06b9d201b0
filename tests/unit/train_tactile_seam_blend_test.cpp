// The tactile map's cross-fade across UV seams (tactile_seam_blend.h): on a cone band whose first
// segment has its own chart turned a quarter round, a map tilted along u everywhere lays reliefs
// that disagree across that chart's two seams (their u axes are a quarter turn apart); after the
// cross-fade the world-space normals on both sides of each seam agree, and a band of 0 leaves the
// map as laid.
#include <tdf/core/tangent_frame.h>
#include <tdf/mesh/uv_seams.h>
#include <tdf/render/texture.h>
#include <tdf/train/tactile_seam_blend.h>
#include <tdf/train/texel_atlas.h>

#include "common/cone_band.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace tdf;

namespace {

// Segments 1..3 share one chart (u in [0.2, 0.8], v in [0, 0.5]); segment 0 has its own,
// u in [0, 0.2] and v in [0.5, 1], turned a quarter round.
TriangleMesh make_turned_band() { return test::make_cone_band(4, 0.2f, 0.5f, 0.8f, 0.6f, true, {0.0f, 0.5f}); }

// World-space normal of texel t of `map` (tangent space) with the frame at its surface point.
Vec3f world_normal(const TriangleMesh& mesh, const TexelAtlas& atlas, const Image& map, std::size_t t) {
    const int f = atlas.raster.triangle[t];
    const Vec3f b = atlas.raster.barycentric[t];
    const Vec3i& p = mesh.triangles[std::size_t(f)];
    const Vec3i& tt = mesh.tangent_triangles[std::size_t(f)];
    TangentFrame frame;
    frame.normal = safe_normalize(mesh.normals[std::size_t(p.x)] * b.x + mesh.normals[std::size_t(p.y)] * b.y +
                                  mesh.normals[std::size_t(p.z)] * b.z);
    frame.tangent = safe_normalize(mesh.tangents[std::size_t(tt.x)].xyz() * b.x +
                                   mesh.tangents[std::size_t(tt.y)].xyz() * b.y +
                                   mesh.tangents[std::size_t(tt.z)].xyz() * b.z);
    frame.handedness = mesh.tangents[std::size_t(tt.x)].w;
    return safe_normalize(tbn_product(frame, {map.data()[3 * t], map.data()[3 * t + 1], map.data()[3 * t + 2]}));
}

// Mean angle (degrees) between the world normals of the texels on either side of the seam edge
// between positions 1 and 5 (segment 0 | segment 1), each side's texels within a texel of it.
double seam_disagreement(const TriangleMesh& mesh, const TexelAtlas& atlas, const Image& map) {
    Vec3f side_sum[2] = {{0, 0, 0}, {0, 0, 0}};
    int counts[2] = {0, 0};
    const float size = float(atlas.size);
    for (const SharedEdge& e : shared_edges(mesh)) {
        if (uv_continuity(mesh, e) != EdgeContinuity::Seam) continue;
        const int lo = mesh.triangles[std::size_t(e.face[0])][e.corner_lo[0]];
        const int hi = mesh.triangles[std::size_t(e.face[0])][e.corner_hi[0]];
        if (lo != 1 || hi != 5) continue;
        for (int s = 0; s < 2; ++s) {
            const Vec2f a = corner_uv(mesh, e.face[s], e.corner_lo[s]) * size;
            const Vec2f b = corner_uv(mesh, e.face[s], e.corner_hi[s]) * size;
            for (std::size_t t = 0; t < atlas.texel_count(); ++t) {
                if (atlas.raster.triangle[t] != e.face[s]) continue;
                const Vec2f c{float(t % std::size_t(atlas.size)) + 0.5f, size - (float(t / std::size_t(atlas.size)) + 0.5f)};
                const Vec2f d = b - a;
                const float along = std::clamp(dot(c - a, d) / dot(d, d), 0.0f, 1.0f);
                if (length(c - (a + d * along)) > 1.0f) continue;
                side_sum[s] += world_normal(mesh, atlas, map, t);
                ++counts[s];
            }
        }
    }
    EXPECT_GT(counts[0], 5);
    EXPECT_GT(counts[1], 5);
    const Vec3f a = safe_normalize(side_sum[0]), b = safe_normalize(side_sum[1]);
    return std::acos(std::clamp(double(dot(a, b)), -1.0, 1.0)) * 180.0 / 3.14159265358979;
}

}  // namespace

TEST(TactileSeamBlend, BothSidesOfATurnedSeamMeetOnTheSurface) {
    const TriangleMesh mesh = make_turned_band();
    const TexelAtlas atlas = TexelAtlas::build(mesh, 128);
    Image tilted(4, 4, 3);
    const Vec3f n = safe_normalize(Vec3f{0.4f, 0.0f, 1.0f});  // 22 degrees toward +u everywhere
    for (std::size_t i = 0; i < tilted.pixel_count(); ++i) std::copy(&n.x, &n.x + 3, tilted.data() + 3 * i);
    const MipTexture texture(tilted);
    SurfaceMaterial material;
    material.tactile = &texture;
    const Image laid = tactile_target(atlas, material);
    const double before = seam_disagreement(mesh, atlas, laid);

    Image unchanged = laid;
    EXPECT_EQ(cross_fade_tactile_seams(unchanged, atlas, mesh, material, 0.0f).blended_texels, 0u);
    EXPECT_EQ(unchanged.values(), laid.values());

    Image blended = laid;
    const SeamBlendStats stats = cross_fade_tactile_seams(blended, atlas, mesh, material, 6.0f);
    const double after = seam_disagreement(mesh, atlas, blended);
    std::printf("turned seam: world normals %.2f deg apart as laid, %.2f after the cross-fade (%zu seam edges, %zu texels)\n",
                before, after, stats.seam_edges, stats.blended_texels);
    EXPECT_EQ(stats.seam_edges, 2u);  // segment 0's chart meets segment 1 and segment 3
    EXPECT_GT(before, 20.0);
    // Texels within one texel of the seam take the other side at a weight of 1/2 falling by 1/12
    // per texel: what is left is at most the laid disagreement over 6 (the band).
    EXPECT_LT(after, before / 6.0);
}
