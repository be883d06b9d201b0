#include <tdf/core/error.h>
#include <tdf/core/force_inline.h>
#include <tdf/core/parallel.h>
#include <tdf/render/trace.h>

#include <cmath>
#include <type_traits>

namespace tdf {

namespace {

// Packet shapes: 16 rays as 4x4 pixels, 8 as 4x2; square-ish blocks keep rays coherent.
template <int N>
struct PacketShape;
template <>
struct PacketShape<16> {
    static constexpr int kW = 4, kH = 4;
    using RayHit = RTCRayHit16;
    static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* r) {
        rtcIntersect16(valid, s, c, r);
    }
};
template <>
struct PacketShape<8> {
    static constexpr int kW = 4, kH = 2;
    using RayHit = RTCRayHit8;
    static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* r) {
        rtcIntersect8(valid, s, c, r);
    }
};

// The primary rays of one packet: the block at (bx, by), lane l at pixel (bx + l % kW, by + l / kW);
// valid[l] is -1 for the lanes inside [.., x1) x [.., y1), else 0. Rays are affine in the pixel
// position: o + do/dx px + do/dy py (same for d); evaluating that directly avoids per-ray
// trigonometry, and equals Camera::generate_ray up to rounding.
template <int N>
class PacketRays {
public:
    using Shape = PacketShape<N>;
    explicit PacketRays(const Camera& camera) : m_ray00(camera.generate_ray(0.f, 0.f)) {
        camera.ray_derivatives(m_do_dx, m_do_dy, m_dd_dx, m_dd_dy);
        rtcInitIntersectContext(&m_context);
        m_context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    }

    // Fills and traces the packet of the block at (bx, by).
    TDF_FORCE_INLINE void trace(const EmbreeScene& scene, int bx, int by, int x1, int y1,
                                typename Shape::RayHit& packet, int* valid) {
        for (int lane = 0; lane < N; ++lane) {
            const int x = bx + lane % Shape::kW, y = by + lane / Shape::kW;
            valid[lane] = (x < x1 && y < y1) ? -1 : 0;
            const float px = float(x) + 0.5f, py = float(y) + 0.5f;
            const Vec3f origin = m_ray00.origin + m_do_dx * px + m_do_dy * py;
            const Vec3f direction = m_ray00.direction + m_dd_dx * px + m_dd_dy * py;
            packet.ray.org_x[lane] = origin.x;
            packet.ray.org_y[lane] = origin.y;
            packet.ray.org_z[lane] = origin.z;
            packet.ray.dir_x[lane] = direction.x;
            packet.ray.dir_y[lane] = direction.y;
            packet.ray.dir_z[lane] = direction.z;
            packet.ray.tnear[lane] = m_ray00.tnear;
            packet.ray.tfar[lane] = m_ray00.tfar;
            packet.ray.time[lane] = 0.f;
            packet.ray.mask[lane] = 0xFFFFFFFFu;
            packet.ray.id[lane] = unsigned(lane);
            packet.ray.flags[lane] = 0;
            packet.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
            packet.hit.instID[0][lane] = RTC_INVALID_GEOMETRY_ID;
        }
        Shape::intersect(valid, scene.handle(), &m_context, &packet);
    }

private:
    Ray m_ray00;
    Vec3f m_do_dx, m_do_dy, m_dd_dx, m_dd_dy;
    RTCIntersectContext m_context;
};

// Shared by the G-buffer tracer and the bare baseline: traces the packets of [x0, x1) x [y0, y1)
// and calls on_lane(pixel_x, pixel_y, lane, rayhit) for every lane inside it (misses included:
// geomID is RTC_INVALID_GEOMETRY_ID).
template <int N, typename OnLane>
void trace_tile_packets(const EmbreeScene& scene, const Camera& camera, int x0, int y0, int x1, int y1,
                        OnLane&& on_lane) {
    using Shape = PacketShape<N>;
    PacketRays<N> rays(camera);
    alignas(64) typename Shape::RayHit packet;
    alignas(64) int valid[N];
    for (int by = y0; by < y1; by += Shape::kH)
        for (int bx = x0; bx < x1; bx += Shape::kW) {
            rays.trace(scene, bx, by, x1, y1, packet, valid);
            for (int lane = 0; lane < N; ++lane)
                if (valid[lane]) on_lane(bx + lane % Shape::kW, by + lane / Shape::kW, lane, packet);
        }
}

// The same a packet at a time: on_packet(bx, by, valid, rayhit). (trace_tile_packets keeps its
// own loop: written as this one with the per-lane loop in the callback, the full-frame G-buffer
// measured 8-15 % slower, BM_GBuffer 23.5-24.7 against 21.3-22.3 ms in five alternating rounds.)
template <int N, typename OnPacket>
void trace_packets(const EmbreeScene& scene, const Camera& camera, int x0, int y0, int x1, int y1,
                   OnPacket&& on_packet) {
    using Shape = PacketShape<N>;
    PacketRays<N> rays(camera);
    alignas(64) typename Shape::RayHit packet;
    alignas(64) int valid[N];
    for (int by = y0; by < y1; by += Shape::kH)
        for (int bx = x0; bx < x1; bx += Shape::kW) {
            rays.trace(scene, bx, by, x1, y1, packet, valid);
            on_packet(bx, by, valid, packet);
        }
}

template <typename OnLane>
void trace_tile_dispatch(const EmbreeScene& scene, const Camera& camera, int x0, int y0, int x1, int y1,
                         OnLane&& on_lane) {
    if (scene.native_packet16())
        trace_tile_packets<16>(scene, camera, x0, y0, x1, y1, on_lane);
    else
        trace_tile_packets<8>(scene, camera, x0, y0, x1, y1, on_lane);
}

inline Vec4f operator*(Vec4f a, float s) { return {a.x * s, a.y * s, a.z * s, a.w * s}; }
inline Vec4f operator+(Vec4f a, Vec4f b) { return {a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w}; }

// Everything per-pixel work needs from one triangle, gathered once and reused while
// neighbouring rays hit the same triangle (typically several pixels in a row). The formulas are
// hit_attributes.h's, which the renderer's lanes use (gbuffer_lanes.cpp), written out here in the
// cached form: with the shared functions the compiler copied the cache's fields through memory
// with loads wider than their stores, and the stalled loads cost the full-frame G-buffer 30-40 %
// (render bench 14-18 -> 21-25 ms). Trace.TileLanesEqualTheFullGBufferBitForBit holds the two to
// the same bits.
class TriangleCache {
public:
    void load(const TriangleMesh& mesh, int f, const RayDerivatives& rd) {
        m_f = f;
        const Vec3i& tri = mesh.triangles[std::size_t(f)];
        p0 = mesh.positions[std::size_t(tri.x)];
        p1 = mesh.positions[std::size_t(tri.y)];
        p2 = mesh.positions[std::size_t(tri.z)];
        n0 = mesh.normals[std::size_t(tri.x)];
        n1 = mesh.normals[std::size_t(tri.y)];
        n2 = mesh.normals[std::size_t(tri.z)];
        has_tangents = !mesh.tangents.empty();
        if (has_tangents) {
            const Vec3i& tt = mesh.tangent_triangles[std::size_t(f)];
            t0 = mesh.tangents[std::size_t(tt.x)];
            t1 = mesh.tangents[std::size_t(tt.y)];
            t2 = mesh.tangents[std::size_t(tt.z)];
        }
        has_uvs = mesh.has_uvs();
        if (!has_uvs) return;
        const Vec3i& ut = mesh.uv_triangles[std::size_t(f)];
        uv0 = mesh.uvs[std::size_t(ut.x)];
        uv1 = mesh.uvs[std::size_t(ut.y)];
        uv2 = mesh.uvs[std::size_t(ut.z)];
        // Ray differentials (Igehy 1999): the hit point moves on the triangle's plane; the
        // barycentric derivatives follow from the Gram matrix of the edges.
        e1 = p1 - p0;
        e2 = p2 - p0;
        ng = cross(e1, e2);
        const float det = dot(ng, ng);  // |e1|^2 |e2|^2 - (e1.e2)^2
        planar = det > 0.f;
        if (!planar) return;
        const float inv_det = 1.f / det;
        a11 = dot(e1, e1) * inv_det;
        a12 = dot(e1, e2) * inv_det;
        a22 = dot(e2, e2) * inv_det;
        min_ng_d_sq = 1e-16f * det;
        du1 = uv1 - uv0;
        du2 = uv2 - uv0;
        ng_do_dx = dot(ng, rd.do_dx);
        ng_do_dy = dot(ng, rd.do_dy);
        ng_dd_dx = dot(ng, rd.dd_dx);
        ng_dd_dy = dot(ng, rd.dd_dy);
    }
    bool holds(int f) const { return f == m_f; }

    // d uv / d pixel at distance t along `direction` (matches the rasterizer's analytic
    // screen-space derivatives of perspective-correct interpolation, spec 3.7).
    void uv_derivatives(Vec3f direction, float t, const RayDerivatives& rd, Vec2f& duv_dx,
                        Vec2f& duv_dy) const {
        if (!planar) {
            duv_dx = duv_dy = {};
            return;
        }
        // Grazing rays: keep |ng.d| >= 1e-8 |ng||d| so the derivatives stay finite.
        float ng_d = dot(ng, direction);
        const float min_sq = min_ng_d_sq * dot(direction, direction);
        if (ng_d * ng_d < min_sq) ng_d = std::copysign(std::sqrt(min_sq), ng_d);
        const float inv_ng_d = 1.f / ng_d;
        auto derivative = [&](Vec3f d_origin, Vec3f d_direction, float ng_do, float ng_dd) {
            const float dt = -(ng_do + t * ng_dd) * inv_ng_d;
            const Vec3f dp = d_origin + d_direction * t + direction * dt;
            const float r1 = dot(e1, dp), r2 = dot(e2, dp);
            return du1 * (a22 * r1 - a12 * r2) + du2 * (a11 * r2 - a12 * r1);
        };
        duv_dx = derivative(rd.do_dx, rd.dd_dx, ng_do_dx, ng_dd_dx);
        duv_dy = derivative(rd.do_dy, rd.dd_dy, ng_do_dy, ng_dd_dy);
    }

    Vec3f p0, p1, p2, n0, n1, n2;
    Vec4f t0, t1, t2;
    Vec2f uv0, uv1, uv2;
    bool has_tangents = false, has_uvs = false;

private:
    int m_f = -1;
    Vec3f e1, e2, ng;
    bool planar = false;
    float a11 = 0, a12 = 0, a22 = 0, min_ng_d_sq = 0;
    Vec2f du1, du2;
    float ng_do_dx = 0, ng_do_dy = 0, ng_dd_dx = 0, ng_dd_dy = 0;
};

void check_inputs(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera) {
    TDF_CHECK_EQ(scene.triangle_count(), mesh.triangles.size());
    TDF_CHECK_EQ(mesh.normals.size(), mesh.positions.size());
    if (camera.width <= 0 || camera.height <= 0)
        throw_error("image size {}x{} is empty (width and height must be positive)", camera.width, camera.height);
}

// Traces [x0, x1) x [y0, y1) of the image into `out`, the image's size.
void trace_region(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera, int x0, int y0,
                  int x1, int y1, GBuffer& out) {
    RayDerivatives rd;
    camera.ray_derivatives(rd.do_dx, rd.do_dy, rd.dd_dx, rd.dd_dy);
    TriangleCache tc;
    const bool ids_and_depth = out.has_ids_and_depth();
    trace_tile_dispatch(scene, camera, x0, y0, x1, y1, [&](int x, int y, int lane, const auto& packet) {
        const std::size_t i = out.index(x, y);
        if (packet.hit.geomID[lane] == RTC_INVALID_GEOMETRY_ID) {
            out.clear_pixel(i);
            return;
        }
        const int f = int(packet.hit.primID[lane]);
        if (!tc.holds(f)) tc.load(mesh, f, rd);
        const float b1 = packet.hit.u[lane], b2 = packet.hit.v[lane], t = packet.ray.tfar[lane];
        const float b0 = 1.f - b1 - b2;
        out.mask[i] = 1.f;
        if (ids_and_depth) {
            out.triangle[i] = f;
            out.barycentric[i] = {b1, b2};
            out.depth[i] = t;  // direction has camera-space z = -1, so t = -z_cam
        }
        out.position[i] = tc.p0 * b0 + tc.p1 * b1 + tc.p2 * b2;
        out.normal[i] = safe_normalize(tc.n0 * b0 + tc.n1 * b1 + tc.n2 * b2);
        if (tc.has_tangents) {
            const Vec4f tw = tc.t0 * b0 + tc.t1 * b1 + tc.t2 * b2;
            out.tangent[i] = safe_normalize(tw.xyz());
            out.handedness[i] = tw.w < 0.f ? -1.f : 1.f;
        } else {
            out.tangent[i] = {};
            out.handedness[i] = 1.f;
        }
        if (tc.has_uvs) {
            out.uv[i] = tc.uv0 * b0 + tc.uv1 * b1 + tc.uv2 * b2;
            const Vec3f direction{packet.ray.dir_x[lane], packet.ray.dir_y[lane], packet.ray.dir_z[lane]};
            tc.uv_derivatives(direction, t, rd, out.duv_dx[i], out.duv_dy[i]);
        } else {
            out.uv[i] = out.duv_dx[i] = out.duv_dy[i] = {};
        }
    });
}

}  // namespace

void trace_tile_lanes(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera, int x0,
                      int y0, int x1, int y1, GBufferLanes& out) {
    TDF_CHECK(x0 >= 0 && y0 >= 0 && x1 <= camera.width && y1 <= camera.height && x0 < x1 && y0 < y1);
    TDF_CHECK((x1 - x0) * (y1 - y0) <= GBufferLanes::kMax);
    RayDerivatives rd;
    camera.ray_derivatives(rd.do_dx, rd.do_dy, rd.dd_dx, rd.dd_dy);
    out.width = x1 - x0;
    out.height = y1 - y0;
    out.count = 0;
    const auto packets = [&](auto width) {
        constexpr int N = decltype(width)::value;
        using Shape = PacketShape<N>;
        trace_packets<N>(
            scene, camera, x0, y0, x1, y1, [&](int bx, int by, const int* valid, const auto& packet) {
                PacketHits hits;
                hits.count = N;
                hits.valid = valid;
                hits.geom_id = packet.hit.geomID;
                hits.prim_id = packet.hit.primID;
                hits.u = packet.hit.u, hits.v = packet.hit.v, hits.t = packet.ray.tfar;
                hits.dir_x = packet.ray.dir_x, hits.dir_y = packet.ray.dir_y, hits.dir_z = packet.ray.dir_z;
                interpolate_packet(mesh, rd, hits, out, out.count);
                for (int lane = 0; lane < N; ++lane)
                    out.pixel[out.count + lane] =
                        valid[lane] ? (by + lane / Shape::kW - y0) * out.width + (bx + lane % Shape::kW - x0)
                                    : -1;
                out.count += N;
            });
    };
    if (scene.native_packet16())
        packets(std::integral_constant<int, 16>{});
    else
        packets(std::integral_constant<int, 8>{});
}

void trace_gbuffer(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera, GBuffer& out,
                   GBufferFields fields) {
    check_inputs(scene, mesh, camera);
    out.resize(camera.width, camera.height, fields);
    parallel_for_tiles(
        camera.width, camera.height, kTraceTileWidth, kTraceTileHeight, [&](int x0, int y0, int x1, int y1) {
            trace_region(scene, mesh, camera, x0, y0, x1, y1, out);
        });
    scene.throw_if_error("tracing");
}

GBuffer trace_gbuffer(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera) {
    GBuffer out;
    trace_gbuffer(scene, mesh, camera, out);
    return out;
}

std::size_t trace_closest_hits(const EmbreeScene& scene, const Camera& camera, std::vector<float>& t) {
    t.assign(std::size_t(camera.width) * std::size_t(camera.height), 0.f);
    std::vector<std::size_t> tile_hits(chunk_count(std::size_t(camera.width), kTraceTileWidth) *
                                       chunk_count(std::size_t(camera.height), kTraceTileHeight));
    const int tiles_x = int(chunk_count(std::size_t(camera.width), kTraceTileWidth));
    parallel_for_tiles(
        camera.width, camera.height, kTraceTileWidth, kTraceTileHeight, [&](int x0, int y0, int x1, int y1) {
            std::size_t hits = 0;
            trace_tile_dispatch(
                scene, camera, x0, y0, x1, y1, [&](int x, int y, int lane, const auto& packet) {
                    const bool hit = packet.hit.geomID[lane] != RTC_INVALID_GEOMETRY_ID;
                    t[std::size_t(y) * std::size_t(camera.width) + std::size_t(x)] =
                        hit ? packet.ray.tfar[lane] : 0.f;
                    hits += hit;
                });
            tile_hits[std::size_t((y0 / kTraceTileHeight) * tiles_x + x0 / kTraceTileWidth)] = hits;
        });
    std::size_t total = 0;
    for (std::size_t h : tile_hits) total += h;
    return total;
}

RayHit trace_ray(const EmbreeScene& scene, const Ray& ray) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh{};
    rh.ray.org_x = ray.origin.x;
    rh.ray.org_y = ray.origin.y;
    rh.ray.org_z = ray.origin.z;
    rh.ray.dir_x = ray.direction.x;
    rh.ray.dir_y = ray.direction.y;
    rh.ray.dir_z = ray.direction.z;
    rh.ray.tnear = ray.tnear;
    rh.ray.tfar = ray.tfar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene.handle(), &context, &rh);
    RayHit hit;
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
        hit.triangle = int(rh.hit.primID);
        hit.barycentric = {rh.hit.u, rh.hit.v};
        hit.t = rh.ray.tfar;
    }
    return hit;
}

}  // namespace tdf
