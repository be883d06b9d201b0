#include <tdf/render/shade_lanes.h>

#include <tdf/core/force_inline.h>
#include <tdf/core/simd_clones.h>

namespace tdf {

namespace {

// One lane: the scalar functions of shading.h, inlined, so the loop below vectorises.
template <bool Training, bool PointLight>
TDF_FORCE_INLINE void shade_lane(const GBufferLanes& g, ShadeLanes& l, const ShadeConstants& c, int i) {
    Vec3f p{l.p[0][i], l.p[1][i], l.p[2][i]};
    if (Training) p = safe_normalize(p);  // spec 3.1 step 5
    const Vec3f raw =
        shading_normal_unnormalized({g.tx[i], g.ty[i], g.tz[i]}, {g.nx[i], g.ny[i], g.nz[i]}, g.w[i], p);
    const Vec3f n = safe_normalize(raw);
    const Vec3f v = Training ? view_space_normal(c.view, n)
                             : Vec3f{dot(c.view.right, raw), dot(c.view.up, raw), dot(c.view.back, raw)};
    const Vec3f to_light =
        PointLight ? safe_normalize(c.light_vector - Vec3f{g.qx[i], g.qy[i], g.qz[i]}) : c.light_vector;
    l.tnx[i] = p.x, l.tny[i] = p.y, l.tnz[i] = p.z;
    l.snx[i] = n.x, l.sny[i] = n.y, l.snz[i] = n.z;
    l.vx[i] = v.x, l.vy[i] = v.y, l.vz[i] = v.z;
    l.shade[i] = visualizer_shade(n, to_light, c.ambient);
}

template <bool Training, bool PointLight>
TDF_FORCE_INLINE void shade_all(const GBufferLanes& g, ShadeLanes& l, const ShadeConstants& c) {
    for (int i = 0; i < l.count; ++i) shade_lane<Training, PointLight>(g, l, c, i);
}

}  // namespace

// Compiled for AVX-512, AVX2 and the x86-64 baseline, picked at load time (GCC target_clones).
// All clones give the same bits: the lanes only add, multiply, divide, take square roots and
// compare (exact in IEEE arithmetic at any vector width), and this file is built with
// -ffp-contract=off (src/CMakeLists.txt): GCC otherwise fuses a*b+c into an FMA in the AVX-512
// clone, which rounds once instead of twice. It is also built without errno for sqrt, so that
// sqrt vectorises.
TDF_SIMD_CLONES
void shade_lanes(const GBufferLanes& g, ShadeLanes& lanes, const ShadeConstants& c) {
    if (c.training)
        c.point_light ? shade_all<true, true>(g, lanes, c) : shade_all<true, false>(g, lanes, c);
    else
        c.point_light ? shade_all<false, true>(g, lanes, c) : shade_all<false, false>(g, lanes, c);
}

}  // namespace tdf
