#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/render/trace.h>

#include <cmath>
#include <type_traits>

#include "hit_attributes.h"

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

// Shared by the G-buffer tracers and the bare baseline: fills one packet with the rays of the
// block at (bx, by) (lane l at pixel (bx + l % kW, by + l / kW)), traces it and calls
// on_packet(bx, by, valid, rayhit); valid[l] is nonzero for the lanes inside [x0, x1) x [y0, y1)
// (misses included: geomID is RTC_INVALID_GEOMETRY_ID).
template <int N, typename OnPacket>
void trace_packets(const EmbreeScene& scene, const Camera& camera, int x0, int y0, int x1, int y1,
                   OnPacket&& on_packet) {
    using Shape = PacketShape<N>;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) typename Shape::RayHit packet;
    alignas(64) int valid[N];
    // Rays are affine in the pixel position: o + do/dx px + do/dy py (same for d). Evaluating
    // that directly avoids per-ray trigonometry; it equals Camera::generate_ray up to rounding.
    const Ray ray00 = camera.generate_ray(0.f, 0.f);
    Vec3f do_dx, do_dy, dd_dx, dd_dy;
    camera.ray_derivatives(do_dx, do_dy, dd_dx, dd_dy);
    for (int by = y0; by < y1; by += Shape::kH) {
        for (int bx = x0; bx < x1; bx += Shape::kW) {
            for (int lane = 0; lane < N; ++lane) {
                const int x = bx + lane % Shape::kW, y = by + lane / Shape::kW;
                valid[lane] = (x < x1 && y < y1) ? -1 : 0;
                const float px = float(x) + 0.5f, py = float(y) + 0.5f;
                const Vec3f origin = ray00.origin + do_dx * px + do_dy * py;
                const Vec3f direction = ray00.direction + dd_dx * px + dd_dy * py;
                packet.ray.org_x[lane] = origin.x;
                packet.ray.org_y[lane] = origin.y;
                packet.ray.org_z[lane] = origin.z;
                packet.ray.dir_x[lane] = direction.x;
                packet.ray.dir_y[lane] = direction.y;
                packet.ray.dir_z[lane] = direction.z;
                packet.ray.tnear[lane] = ray00.tnear;
                packet.ray.tfar[lane] = ray00.tfar;
                packet.ray.time[lane] = 0.f;
                packet.ray.mask[lane] = 0xFFFFFFFFu;
                packet.ray.id[lane] = unsigned(lane);
                packet.ray.flags[lane] = 0;
                packet.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
                packet.hit.instID[0][lane] = RTC_INVALID_GEOMETRY_ID;
            }
            Shape::intersect(valid, scene.handle(), &context, &packet);
            on_packet(bx, by, valid, packet);
        }
    }
}

// The packets' lanes one at a time: on_lane(pixel_x, pixel_y, lane, rayhit) for every lane inside
// [x0, x1) x [y0, y1).
template <typename OnLane>
void trace_tile_dispatch(const EmbreeScene& scene, const Camera& camera, int x0, int y0, int x1, int y1,
                         OnLane&& on_lane) {
    const auto lanes = [&](auto width) {
        using Shape = PacketShape<decltype(width)::value>;
        trace_packets<decltype(width)::value>(
            scene, camera, x0, y0, x1, y1, [&](int bx, int by, const int* valid, const auto& packet) {
                for (int lane = 0; lane < decltype(width)::value; ++lane)
                    if (valid[lane]) on_lane(bx + lane % Shape::kW, by + lane / Shape::kW, lane, packet);
            });
    };
    if (scene.native_packet16())
        lanes(std::integral_constant<int, 16>{});
    else
        lanes(std::integral_constant<int, 8>{});
}

// Everything per-pixel work needs from one triangle, gathered once and reused while
// neighbouring rays hit the same triangle (typically several pixels in a row).
class TriangleCache {
public:
    void load(const TriangleMesh& mesh, int f, const RayDerivatives& rd) {
        m_f = f;
        const Vec3i& tri = mesh.triangles[std::size_t(f)];
        corners.p0 = mesh.positions[std::size_t(tri.x)];
        corners.p1 = mesh.positions[std::size_t(tri.y)];
        corners.p2 = mesh.positions[std::size_t(tri.z)];
        corners.n0 = mesh.normals[std::size_t(tri.x)];
        corners.n1 = mesh.normals[std::size_t(tri.y)];
        corners.n2 = mesh.normals[std::size_t(tri.z)];
        has_tangents = !mesh.tangents.empty();
        if (has_tangents) {
            const Vec3i& tt = mesh.tangent_triangles[std::size_t(f)];
            corners.t0 = mesh.tangents[std::size_t(tt.x)];
            corners.t1 = mesh.tangents[std::size_t(tt.y)];
            corners.t2 = mesh.tangents[std::size_t(tt.z)];
        }
        has_uvs = mesh.has_uvs();
        if (!has_uvs) return;
        const Vec3i& ut = mesh.uv_triangles[std::size_t(f)];
        corners.uv0 = mesh.uvs[std::size_t(ut.x)];
        corners.uv1 = mesh.uvs[std::size_t(ut.y)];
        corners.uv2 = mesh.uvs[std::size_t(ut.z)];
        terms = hit_attributes::triangle_terms(corners, rd);
    }
    bool holds(int f) const { return f == m_f; }

    hit_attributes::Hit interpolate(float b1, float b2, float t, Vec3f direction,
                                    const RayDerivatives& rd) const {
        using hit_attributes::interpolate_hit;
        if (has_tangents)
            return has_uvs ? interpolate_hit<true, true>(corners, terms, b1, b2, t, direction, rd)
                           : interpolate_hit<true, false>(corners, terms, b1, b2, t, direction, rd);
        return has_uvs ? interpolate_hit<false, true>(corners, terms, b1, b2, t, direction, rd)
                       : interpolate_hit<false, false>(corners, terms, b1, b2, t, direction, rd);
    }

private:
    int m_f = -1;
    bool has_tangents = false, has_uvs = false;
    hit_attributes::Corners corners;
    hit_attributes::TriangleTerms terms{};
};

void check_inputs(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera) {
    TDF_CHECK_EQ(scene.triangle_count(), mesh.triangles.size());
    TDF_CHECK_EQ(mesh.normals.size(), mesh.positions.size());
    if (camera.width <= 0 || camera.height <= 0)
        throw_error("image size {}x{} is empty (width and height must be positive)", camera.width, camera.height);
}

// Traces [x0, x1) x [y0, y1) and stores pixel (x, y) at out.index(x - ox, y - oy).
void trace_region(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera, int x0, int y0, int x1,
                  int y1, GBuffer& out, int ox, int oy) {
    RayDerivatives rd;
    camera.ray_derivatives(rd.do_dx, rd.do_dy, rd.dd_dx, rd.dd_dy);
    TriangleCache tc;
    const bool ids_and_depth = out.has_ids_and_depth();
    trace_tile_dispatch(scene, camera, x0, y0, x1, y1, [&](int x, int y, int lane, const auto& packet) {
        const std::size_t i = out.index(x - ox, y - oy);
        if (packet.hit.geomID[lane] == RTC_INVALID_GEOMETRY_ID) {
            out.clear_pixel(i);
            return;
        }
        const int f = int(packet.hit.primID[lane]);
        if (!tc.holds(f)) tc.load(mesh, f, rd);
        const float b1 = packet.hit.u[lane], b2 = packet.hit.v[lane], t = packet.ray.tfar[lane];
        const Vec3f direction{packet.ray.dir_x[lane], packet.ray.dir_y[lane], packet.ray.dir_z[lane]};
        const hit_attributes::Hit hit = tc.interpolate(b1, b2, t, direction, rd);
        out.mask[i] = 1.f;
        if (ids_and_depth) {
            out.triangle[i] = f;
            out.barycentric[i] = {b1, b2};
            out.depth[i] = t;  // direction has camera-space z = -1, so t = -z_cam
        }
        out.position[i] = hit.position;
        out.normal[i] = hit.normal;
        out.tangent[i] = hit.tangent;
        out.handedness[i] = hit.handedness;
        out.uv[i] = hit.uv;
        out.duv_dx[i] = hit.duv.dx;
        out.duv_dy[i] = hit.duv.dy;
    });
}

}  // namespace

void trace_tile(const EmbreeScene& scene, const TriangleMesh& mesh, const Camera& camera, int x0, int y0, int x1,
                int y1, GBuffer& tile) {
    TDF_CHECK(x0 >= 0 && y0 >= 0 && x1 <= camera.width && y1 <= camera.height && x0 < x1 && y0 < y1);
    if (tile.width != x1 - x0 || tile.height != y1 - y0) tile.resize(x1 - x0, y1 - y0);
    trace_region(scene, mesh, camera, x0, y0, x1, y1, tile, x0, y0);
}

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
            trace_region(scene, mesh, camera, x0, y0, x1, y1, out, 0, 0);
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
