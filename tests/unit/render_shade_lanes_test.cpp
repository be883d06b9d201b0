// The vectorised shading lanes (shade_lanes.h) against the scalar functions of shading.h they
// inline: every output bit for bit, in the clone this CPU runs (AVX-512, AVX2 or baseline), for
// both shading modes and both light kinds, including background lanes (zero frames).
#include <tdf/core/rng.h>
#include <tdf/render/shade_lanes.h>

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

using namespace tdf;

namespace {

Vec3f random_vec(Rng& rng) { return {rng.normal(), rng.normal(), rng.normal()}; }

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

void expect_same_bits(Vec3f lanes, Vec3f scalar, const char* what, int i) {
    for (int k = 0; k < 3; ++k)
        EXPECT_TRUE(same_bits(lanes[k], scalar[k]))
            << what << " lane " << i << " component " << k << ": " << lanes[k] << " vs " << scalar[k];
}

}  // namespace

TEST(ShadeLanes, EqualTheScalarShadingBitForBit) {
    Rng rng(25);
    auto lanes = std::make_unique<ShadeLanes>();
    auto geometry = std::make_unique<GBufferLanes>();
    ShadeLanes& l = *lanes;
    GBufferLanes& g = *geometry;
    l.count = g.count = ShadeLanes::kMax - 3;  // not a multiple of the vector width: the loop's tail too
    for (int i = 0; i < l.count; ++i) {
        // Every 7th lane is background: a zero frame and position, a flat tactile normal.
        const bool background = i % 7 == 0;
        const Vec3f n = background ? Vec3f{} : random_vec(rng), t = background ? Vec3f{} : random_vec(rng);
        const Vec3f q = background ? Vec3f{} : random_vec(rng);
        const Vec3f p = background ? Vec3f{0, 0, 1} : random_vec(rng);
        g.nx[i] = n.x, g.ny[i] = n.y, g.nz[i] = n.z;
        g.tx[i] = t.x, g.ty[i] = t.y, g.tz[i] = t.z;
        g.w[i] = i % 2 ? 1.f : -1.f;
        g.qx[i] = q.x, g.qy[i] = q.y, g.qz[i] = q.z;
        l.p[0][i] = p.x, l.p[1][i] = p.y, l.p[2][i] = p.z;
    }
    ShadeConstants c;
    c.view = {safe_normalize({1, 0.2f, 0}), safe_normalize({-0.2f, 1, 0.1f}), safe_normalize({0, -0.1f, 1})};
    for (bool training : {true, false})
        for (bool point : {true, false}) {
            c.training = training;
            c.point_light = point;
            c.light_vector = point ? Vec3f{2, 3, 4} : safe_normalize({0.3f, 0.5f, 0.8f});
            c.ambient = training ? 0.5f : 0.1f;
            shade_lanes(g, l, c);
            for (int i = 0; i < l.count; ++i) {
                Vec3f p{l.p[0][i], l.p[1][i], l.p[2][i]};
                if (training) p = safe_normalize(p);
                const Vec3f raw = shading_normal_unnormalized(
                    {g.tx[i], g.ty[i], g.tz[i]}, {g.nx[i], g.ny[i], g.nz[i]}, g.w[i], p);
                const Vec3f n = safe_normalize(raw);
                const Vec3f v = training ? view_space_normal(c.view, n)
                                         : Vec3f{dot(c.view.right, raw), dot(c.view.up, raw), dot(c.view.back, raw)};
                const Vec3f to_light = point
                                           ? safe_normalize(c.light_vector - Vec3f{g.qx[i], g.qy[i], g.qz[i]})
                                           : c.light_vector;
                expect_same_bits({l.tnx[i], l.tny[i], l.tnz[i]}, p, "tactile normal", i);
                expect_same_bits({l.snx[i], l.sny[i], l.snz[i]}, n, "shading normal", i);
                expect_same_bits({l.vx[i], l.vy[i], l.vz[i]}, v, "view-space normal", i);
                EXPECT_TRUE(same_bits(l.shade[i], visualizer_shade(n, to_light, c.ambient))) << "shade lane " << i;
            }
        }
}
