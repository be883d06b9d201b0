#pragma once
/// One tile of a G-buffer in structure-of-arrays form, one array per component: what the
/// renderer's shading reads (shade_lanes.h, the texture lookups) without converting GBuffer's
/// per-pixel vectors. The tracer fills it a packet at a time, in packet order (trace_tile_lanes in
/// trace.h); `pixel` says where each lane lies in the tile.
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>

#include <cstddef>

namespace tdf {

struct GBuffer;

/// Camera ray derivatives, constant over the image: d origin / d pixel and d direction / d pixel.
struct RayDerivatives {
    Vec3f do_dx, do_dy, dd_dx, dd_dy;
};

struct GBufferLanes {
    static constexpr int kMax = 256;  ///< the lanes of a trace tile (trace.h)
    int count = 0;                    ///< lanes in use
    int width = 0, height = 0;        ///< the tile's size in pixels
    /// Each lane's tile pixel (y * width + x), or -1 for a lane of a packet that lies outside the
    /// image (mask 0). Every tile pixel is exactly one lane's.
    alignas(64) int pixel[kMax];
    // GBuffer's fields (gbuffer.h), background lanes as GBuffer::clear_pixel leaves them.
    alignas(64) float mask[kMax];
    alignas(64) int triangle[kMax];
    alignas(64) float b1[kMax], b2[kMax], depth[kMax];
    alignas(64) float qx[kMax], qy[kMax], qz[kMax];  ///< position
    alignas(64) float nx[kMax], ny[kMax], nz[kMax];
    alignas(64) float tx[kMax], ty[kMax], tz[kMax], w[kMax];  ///< tangent and handedness
    alignas(64) float u[kMax], v[kMax];
    alignas(64) float du_dx[kMax], dv_dx[kMax], du_dy[kMax], dv_dy[kMax];

    /// The lanes of a tile `tile` (at most kMax pixels), in row-major order: for producers that
    /// fill a GBuffer tile (the rasterizer's interpolate_tile).
    void assign(const GBuffer& tile);
};

/// One packet's rays and hits as Embree leaves them (pointers into an RTCRayHit8 or 16).
struct PacketHits {
    int count = 0;  ///< lanes: 8 or 16
    const int* valid = nullptr;
    const unsigned* geom_id = nullptr;
    const unsigned* prim_id = nullptr;
    const float *u = nullptr, *v = nullptr, *t = nullptr;
    const float *dir_x = nullptr, *dir_y = nullptr, *dir_z = nullptr;
};

/// Lanes [first, first + hits.count) of `out` from one packet's hits on `mesh` (the mesh the
/// traced scene was built from); trace_gbuffer writes these lanes out. Vectorised
/// (AVX-512, AVX2 or the baseline, picked at load time). Does not set `pixel`.
void interpolate_packet(const TriangleMesh& mesh, const RayDerivatives& rd, const PacketHits& hits,
                        GBufferLanes& out, int first);

}  // namespace tdf
