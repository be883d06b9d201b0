#pragma once
// One ray hit's surface attributes from its triangle's corners, per lane: what the G-buffer lanes
// hold for a pixel (gbuffer_lanes.cpp, vectorised over a packet), the renderer's tiles and, written
// out, the full-frame G-buffer (trace_gbuffer). Trace.FullGBufferHoldsThePlainInterpolationOfEachHit
// checks them against the plain per-pixel formulas.
#include <tdf/core/force_inline.h>
#include <tdf/core/vec.h>
#include <tdf/render/gbuffer_lanes.h>

#include <cmath>

namespace tdf::hit_attributes {

TDF_FORCE_INLINE Vec4f operator*(Vec4f a, float s) { return {a.x * s, a.y * s, a.z * s, a.w * s}; }
TDF_FORCE_INLINE Vec4f operator+(Vec4f a, Vec4f b) { return {a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w}; }

// A triangle's corners: positions, normals, tangents (w: handedness) and UVs.
struct Corners {
    Vec3f p0, p1, p2, n0, n1, n2;
    Vec4f t0, t1, t2;
    Vec2f uv0, uv1, uv2;
};

// What the UV derivatives need of a triangle and the camera, whatever the ray.
struct TriangleTerms {
    Vec3f e1, e2, ng;
    bool planar;
    float a11, a12, a22, min_ng_d_sq;
    Vec2f du1, du2;
    float ng_do_dx, ng_do_dy, ng_dd_dx, ng_dd_dy;
};

// Ray differentials (Igehy 1999): the hit point moves on the triangle's plane; the barycentric
// derivatives follow from the Gram matrix of the edges. (A degenerate triangle's terms are not
// finite; uv_derivatives() does not use them.)
TDF_FORCE_INLINE TriangleTerms triangle_terms(Vec3f p0, Vec3f p1, Vec3f p2, Vec2f uv0, Vec2f uv1, Vec2f uv2,
                                              const RayDerivatives& rd) {
    TriangleTerms t;
    t.e1 = p1 - p0;
    t.e2 = p2 - p0;
    t.ng = cross(t.e1, t.e2);
    const float det = dot(t.ng, t.ng);  // |e1|^2 |e2|^2 - (e1.e2)^2
    t.planar = det > 0.f;
    const float inv_det = 1.f / det;
    t.a11 = dot(t.e1, t.e1) * inv_det;
    t.a12 = dot(t.e1, t.e2) * inv_det;
    t.a22 = dot(t.e2, t.e2) * inv_det;
    t.min_ng_d_sq = 1e-16f * det;
    t.du1 = uv1 - uv0;
    t.du2 = uv2 - uv0;
    t.ng_do_dx = dot(t.ng, rd.do_dx);
    t.ng_do_dy = dot(t.ng, rd.do_dy);
    t.ng_dd_dx = dot(t.ng, rd.dd_dx);
    t.ng_dd_dy = dot(t.ng, rd.dd_dy);
    return t;
}

// d uv / d pixel x and y at distance t along `direction` (matches the rasterizer's analytic
// screen-space derivatives of perspective-correct interpolation, spec 3.7); zero on a degenerate
// triangle. Branch-free (selects), so that the lanes' loop vectorises.
struct UvDerivatives {
    Vec2f dx, dy;
};
TDF_FORCE_INLINE UvDerivatives uv_derivatives(const TriangleTerms& tt, Vec3f direction, float t,
                                              const RayDerivatives& rd) {
    // Grazing rays: keep |ng.d| >= 1e-8 |ng||d| so the derivatives stay finite.
    const float ng_d_raw = dot(tt.ng, direction);
    const float min_sq = tt.min_ng_d_sq * dot(direction, direction);
    const float ng_d = ng_d_raw * ng_d_raw < min_sq ? std::copysign(std::sqrt(min_sq), ng_d_raw) : ng_d_raw;
    const float inv_ng_d = 1.f / ng_d;
    const auto derivative = [&](Vec3f d_origin, Vec3f d_direction, float ng_do, float ng_dd) {
        const float dt = -(ng_do + t * ng_dd) * inv_ng_d;
        const Vec3f dp = d_origin + d_direction * t + direction * dt;
        const float r1 = dot(tt.e1, dp), r2 = dot(tt.e2, dp);
        const Vec2f d = tt.du1 * (tt.a22 * r1 - tt.a12 * r2) + tt.du2 * (tt.a11 * r2 - tt.a12 * r1);
        return Vec2f{tt.planar ? d.x : 0.f, tt.planar ? d.y : 0.f};
    };
    return {derivative(rd.do_dx, rd.dd_dx, tt.ng_do_dx, tt.ng_dd_dx),
            derivative(rd.do_dy, rd.dd_dy, tt.ng_do_dy, tt.ng_dd_dy)};
}

// The attributes at barycentrics (b1, b2) of a hit at distance t along `direction`, handed to
// emit(position, normal, tangent, handedness, uv, duv_dx, duv_dy), which writes them straight into
// the caller's lanes; a mesh without tangents has tangent 0 and handedness +1, one without UVs UV 0
// and derivatives 0.
template <bool Tangents, bool Uvs, typename Emit>
TDF_FORCE_INLINE void interpolate_hit(const Corners& c, const TriangleTerms& tt, float b1, float b2, float t,
                                      Vec3f direction, const RayDerivatives& rd, Emit&& emit) {
    const float b0 = 1.f - b1 - b2;
    const Vec3f position = c.p0 * b0 + c.p1 * b1 + c.p2 * b2;
    const Vec3f normal = safe_normalize(c.n0 * b0 + c.n1 * b1 + c.n2 * b2);
    Vec3f tangent;
    float handedness = 1.f;
    if constexpr (Tangents) {
        const Vec4f tw = c.t0 * b0 + c.t1 * b1 + c.t2 * b2;
        tangent = safe_normalize(tw.xyz());
        handedness = tw.w < 0.f ? -1.f : 1.f;
    }
    if constexpr (Uvs) {
        const UvDerivatives d = uv_derivatives(tt, direction, t, rd);
        emit(position, normal, tangent, handedness, c.uv0 * b0 + c.uv1 * b1 + c.uv2 * b2, d.dx, d.dy);
    } else {
        emit(position, normal, tangent, handedness, Vec2f{}, Vec2f{}, Vec2f{});
    }
}

}  // namespace tdf::hit_attributes
