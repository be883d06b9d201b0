#include <tdf/core/error.h>
#include <tdf/core/simd_clones.h>
#include <tdf/render/gbuffer.h>
#include <tdf/render/gbuffer_lanes.h>

#include "hit_attributes.h"

#include <vector>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace tdf {

void GBufferLanes::assign(const GBuffer& g) {
    TDF_CHECK(g.pixel_count() <= std::size_t(kMax));
    width = g.width;
    height = g.height;
    count = int(g.pixel_count());
    const bool ids = g.has_ids_and_depth();
    for (int i = 0; i < count; ++i) {
        const std::size_t k = std::size_t(i);
        pixel[i] = i;
        mask[i] = g.mask[k];
        triangle[i] = ids ? g.triangle[k] : -1;
        b1[i] = ids ? g.barycentric[k].x : 0.f;
        b2[i] = ids ? g.barycentric[k].y : 0.f;
        depth[i] = ids ? g.depth[k] : 0.f;
        qx[i] = g.position[k].x, qy[i] = g.position[k].y, qz[i] = g.position[k].z;
        nx[i] = g.normal[k].x, ny[i] = g.normal[k].y, nz[i] = g.normal[k].z;
        tx[i] = g.tangent[k].x, ty[i] = g.tangent[k].y, tz[i] = g.tangent[k].z, w[i] = g.handedness[k];
        u[i] = g.uv[k].x, v[i] = g.uv[k].y;
        du_dx[i] = g.duv_dx[k].x, dv_dx[i] = g.duv_dx[k].y, du_dy[i] = g.duv_dy[k].x,
        dv_dy[i] = g.duv_dy[k].y;
    }
}

namespace {

// Embree's RTC_INVALID_GEOMETRY_ID, without Embree's headers in this file.
constexpr unsigned kNoGeometry = ~0u;
constexpr int kPacketMax = 16;

// Each lane's triangle corners in rows of lanes: the vector loop below reads them as it reads any
// array. (Scalar loads: on AMD's AVX-512 the vector clones' gathers are emulated element by
// element, and measured slower; session 12.)
struct CornerRows {
    enum { kPosition = 0, kNormal = 9, kTangent = 18, kUv = 30, kRows = 36 };
    alignas(64) float row[kRows][kPacketMax];
    alignas(64) int hit[kPacketMax];
    alignas(64) int triangle[kPacketMax];
};

#if defined(__SSE2__)
// Four lanes' registers of up to four floats each (lanes i .. i + 3), transposed into the rows
// row .. row + rows - 1 of those lanes.
TDF_FORCE_INLINE void put_four(CornerRows& c, int row, int rows, int i, __m128 l0, __m128 l1, __m128 l2, __m128 l3) {
    _MM_TRANSPOSE4_PS(l0, l1, l2, l3);
    _mm_store_ps(&c.row[row][i], l0);
    _mm_store_ps(&c.row[row + 1][i], l1);
    if (rows > 2) _mm_store_ps(&c.row[row + 2][i], l2);
    if (rows > 3) _mm_store_ps(&c.row[row + 3][i], l3);
}

// A Vec3f's three floats and one more (the next element's first, unused): one load. The array's
// last element has no next; it is assembled from its three floats.
struct Vec3Loader {
    const Vec3f* data;
    std::size_t last;
    explicit Vec3Loader(const std::vector<Vec3f>& v) : data(v.data()), last(v.size() - 1) {}
    TDF_FORCE_INLINE __m128 operator()(int index) const {
        const Vec3f& p = data[index];
        if (__builtin_expect(std::size_t(index) < last, 1)) return _mm_loadu_ps(&p.x);
        return _mm_setr_ps(p.x, p.y, p.z, 0.f);
    }
};
#endif

template <bool Tangents, bool Uvs>
TDF_FORCE_INLINE void gather_corners(const TriangleMesh& mesh, CornerRows& c, int count) {
#if defined(__SSE2__)
    // Four lanes at a time: each corner's attribute loaded whole into a register, four lanes'
    // transposed into rows (a quarter of the scalar copy's stores; count is 8 or 16).
    const Vec3Loader positions(mesh.positions), normals(mesh.normals);
    for (int i = 0; i < count; i += 4) {
        Vec3i tri[4], tt[4], ut[4];
        for (int j = 0; j < 4; ++j) {
            // Lanes that missed read triangle 0, whose results they then discard.
            const std::size_t f = std::size_t(c.hit[i + j] ? c.triangle[i + j] : 0);
            tri[j] = mesh.triangles[f];
            if (Tangents) tt[j] = mesh.tangent_triangles[f];
            if (Uvs) ut[j] = mesh.uv_triangles[f];
        }
        for (int k = 0; k < 3; ++k) {
            put_four(c, CornerRows::kPosition + 3 * k, 3, i, positions(tri[0][k]), positions(tri[1][k]),
                     positions(tri[2][k]), positions(tri[3][k]));
            put_four(c, CornerRows::kNormal + 3 * k, 3, i, normals(tri[0][k]), normals(tri[1][k]),
                     normals(tri[2][k]), normals(tri[3][k]));
            if (Tangents) {
                const auto t = [&](int j) { return _mm_loadu_ps(&mesh.tangents[std::size_t(tt[j][k])].x); };
                put_four(c, CornerRows::kTangent + 4 * k, 4, i, t(0), t(1), t(2), t(3));
            }
        }
        if (Uvs) {
            const auto at = [&](int j, int k) { return reinterpret_cast<const __m64*>(&mesh.uvs[std::size_t(ut[j][k])]); };
            const auto uv = [&](int j, int k) { return _mm_loadl_pi(_mm_setzero_ps(), at(j, k)); };
            // (u, v) of corners k0 and k1
            const auto two = [&](int j, int k0, int k1) { return _mm_loadh_pi(uv(j, k0), at(j, k1)); };
            put_four(c, CornerRows::kUv, 4, i, two(0, 0, 1), two(1, 0, 1), two(2, 0, 1), two(3, 0, 1));
            put_four(c, CornerRows::kUv + 4, 2, i, uv(0, 2), uv(1, 2), uv(2, 2), uv(3, 2));
        }
    }
#else
    for (int i = 0; i < count; ++i) {
        // Lanes that missed read triangle 0, whose results they then discard.
        const std::size_t f = std::size_t(c.hit[i] ? c.triangle[i] : 0);
        const Vec3i& tri = mesh.triangles[f];
        for (int k = 0; k < 3; ++k) {
            const Vec3f& p = mesh.positions[std::size_t(tri[k])];
            const Vec3f& n = mesh.normals[std::size_t(tri[k])];
            for (int d = 0; d < 3; ++d) {
                c.row[CornerRows::kPosition + 3 * k + d][i] = p[d];
                c.row[CornerRows::kNormal + 3 * k + d][i] = n[d];
            }
        }
        if (Tangents) {
            const Vec3i& tt = mesh.tangent_triangles[f];
            for (int k = 0; k < 3; ++k) {
                const Vec4f& t = mesh.tangents[std::size_t(tt[k])];
                for (int d = 0; d < 4; ++d) c.row[CornerRows::kTangent + 4 * k + d][i] = t[d];
            }
        }
        if (Uvs) {
            const Vec3i& ut = mesh.uv_triangles[f];
            for (int k = 0; k < 3; ++k) {
                const Vec2f& uv = mesh.uvs[std::size_t(ut[k])];
                c.row[CornerRows::kUv + 2 * k][i] = uv.x;
                c.row[CornerRows::kUv + 2 * k + 1][i] = uv.y;
            }
        }
    }
#endif
}

template <bool Tangents, bool Uvs>
TDF_FORCE_INLINE void interpolate_lane(const CornerRows& c, const RayDerivatives& rd, const PacketHits& h,
                                       int i, GBufferLanes& out, int o) {
    using namespace hit_attributes;
    const auto v3 = [&](int row) { return Vec3f{c.row[row][i], c.row[row + 1][i], c.row[row + 2][i]}; };
    const auto v4 = [&](int row) { return Vec4f{v3(row), c.row[row + 3][i]}; };
    const auto v2 = [&](int row) { return Vec2f{c.row[row][i], c.row[row + 1][i]}; };
    Corners corners;
    corners.p0 = v3(CornerRows::kPosition), corners.p1 = v3(CornerRows::kPosition + 3);
    corners.p2 = v3(CornerRows::kPosition + 6);
    corners.n0 = v3(CornerRows::kNormal), corners.n1 = v3(CornerRows::kNormal + 3);
    corners.n2 = v3(CornerRows::kNormal + 6);
    if (Tangents) {
        corners.t0 = v4(CornerRows::kTangent), corners.t1 = v4(CornerRows::kTangent + 4);
        corners.t2 = v4(CornerRows::kTangent + 8);
    }
    if (Uvs) {
        corners.uv0 = v2(CornerRows::kUv), corners.uv1 = v2(CornerRows::kUv + 2);
        corners.uv2 = v2(CornerRows::kUv + 4);
    }
    const bool hit = c.hit[i] != 0;
    // Misses carry whatever Embree left in u, v and tfar: zero them so that no lane computes on
    // garbage (the loads are unconditional so that the selects vectorise).
    const float hu = h.u[i], hv = h.v[i], ht = h.t[i];
    const float b1 = hit ? hu : 0.f, b2 = hit ? hv : 0.f, t = hit ? ht : 0.f;
    const Vec3f direction{h.dir_x[i], h.dir_y[i], h.dir_z[i]};
    const TriangleTerms terms =
        Uvs ? triangle_terms(corners.p0, corners.p1, corners.p2, corners.uv0, corners.uv1, corners.uv2, rd)
            : TriangleTerms{};
    const auto keep = [hit](float value) { return hit ? value : 0.f; };
    out.mask[o] = hit ? 1.f : 0.f;
    out.triangle[o] = hit ? c.triangle[i] : -1;
    out.b1[o] = b1, out.b2[o] = b2, out.depth[o] = t;  // direction has camera-space z = -1, so t = -z_cam
    interpolate_hit<Tangents, Uvs>(
        corners,
        terms,
        b1,
        b2,
        t,
        direction,
        rd,
        [&](Vec3f position,
            Vec3f normal,
            Vec3f tangent,
            float handedness,
            Vec2f uv,
            Vec2f duv_dx,
            Vec2f duv_dy) {
            out.qx[o] = keep(position.x), out.qy[o] = keep(position.y), out.qz[o] = keep(position.z);
            out.nx[o] = keep(normal.x), out.ny[o] = keep(normal.y), out.nz[o] = keep(normal.z);
            out.tx[o] = keep(tangent.x), out.ty[o] = keep(tangent.y), out.tz[o] = keep(tangent.z);
            out.w[o] = keep(handedness);
            out.u[o] = keep(uv.x), out.v[o] = keep(uv.y);
            out.du_dx[o] = keep(duv_dx.x), out.dv_dx[o] = keep(duv_dx.y);
            out.du_dy[o] = keep(duv_dy.x), out.dv_dy[o] = keep(duv_dy.y);
        });
}

template <bool Tangents, bool Uvs>
TDF_FORCE_INLINE void interpolate_all(const TriangleMesh& mesh, const RayDerivatives& rd, const PacketHits& h,
                                      CornerRows& c, GBufferLanes& out, int first) {
    gather_corners<Tangents, Uvs>(mesh, c, h.count);
    for (int i = 0; i < h.count; ++i) interpolate_lane<Tangents, Uvs>(c, rd, h, i, out, first + i);
}

}  // namespace

// Compiled for AVX-512, AVX2 and the x86-64 baseline, picked at load time (GCC target_clones).
// All clones give the scalar tracer's bits: the lanes only add, multiply, divide, take square
// roots, copy signs and compare (exact in IEEE arithmetic at any vector width), and this file is
// built with -ffp-contract=off and without errno for sqrt, as shade_lanes.cpp is
// (src/CMakeLists.txt).
TDF_SIMD_CLONES
void interpolate_packet(const TriangleMesh& mesh, const RayDerivatives& rd, const PacketHits& h,
                        GBufferLanes& out, int first) {
    TDF_CHECK(h.count <= kPacketMax && first + h.count <= GBufferLanes::kMax);
    CornerRows corners;  // on the stack: the vectoriser does not take thread-local arrays
    int hits = 0;
    for (int i = 0; i < h.count; ++i) {
        corners.hit[i] = (h.valid[i] != 0) & (h.geom_id[i] != kNoGeometry);
        corners.triangle[i] = int(h.prim_id[i]);
        hits += corners.hit[i];
    }
    if (hits == 0) {
        // The whole packet missed (a quarter of a typical frame): no corners to gather.
        for (int o = first; o < first + h.count; ++o) {
            out.mask[o] = 0.f, out.triangle[o] = -1, out.b1[o] = out.b2[o] = out.depth[o] = 0.f;
            out.qx[o] = out.qy[o] = out.qz[o] = out.nx[o] = out.ny[o] = out.nz[o] = 0.f;
            out.tx[o] = out.ty[o] = out.tz[o] = out.w[o] = 0.f;
            out.u[o] = out.v[o] = out.du_dx[o] = out.dv_dx[o] = out.du_dy[o] = out.dv_dy[o] = 0.f;
        }
        return;
    }
    const bool tangents = !mesh.tangents.empty(), uvs = mesh.has_uvs();
    if (tangents)
        uvs ? interpolate_all<true, true>(mesh, rd, h, corners, out, first)
            : interpolate_all<true, false>(mesh, rd, h, corners, out, first);
    else
        uvs ? interpolate_all<false, true>(mesh, rd, h, corners, out, first)
            : interpolate_all<false, false>(mesh, rd, h, corners, out, first);
}

}  // namespace tdf
