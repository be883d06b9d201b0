#include <tdf/core/error.h>
#include <tdf/render/gbuffer.h>
#include <tdf/render/stream_lanes.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace tdf {

void TilePixelLanes::build(const GBufferLanes& lanes) {
    TDF_CHECK(lanes.width * lanes.height <= GBufferLanes::kMax);
    m_width = lanes.width;
    m_height = lanes.height;
    m_runs_per_row = (m_width + 3) / 4;
    for (int i = 0; i < lanes.count; ++i)
        if (lanes.pixel[i] >= 0) m_lane[lanes.pixel[i]] = i;
    for (int y = 0; y < m_height; ++y)
        for (int x = 0; x < m_width; x += 4) {
            const int* run = m_lane + y * m_width + x;
            const bool four =
                x + 4 <= m_width && run[1] == run[0] + 1 && run[2] == run[0] + 2 && run[3] == run[0] + 3;
            m_run[y * m_runs_per_row + x / 4] = four ? run[0] : -1;
        }
}

namespace {

#if defined(__SSE2__)
// Four pixels of C channels from the four lanes from `lane` on, interleaved in registers and
// written with streaming stores to `out` (16-byte aligned); with Masked, zeros where hits is not > 0.
template <int C, bool Masked>
inline void stream_four(const float* const* planes, const float* hits, int lane, float* out) {
    const __m128 keep = Masked ? _mm_cmpgt_ps(_mm_loadu_ps(hits + lane), _mm_setzero_ps()) : __m128{};
    const auto load = [&](int k) {
        const __m128 v = _mm_loadu_ps(planes[k] + lane);
        return Masked ? _mm_and_ps(v, keep) : v;
    };
    if constexpr (C == 1) {
        _mm_stream_ps(out, load(0));
    } else if constexpr (C == 2) {
        const __m128 u = load(0), v = load(1);
        _mm_stream_ps(out, _mm_unpacklo_ps(u, v));      // u0 v0 u1 v1
        _mm_stream_ps(out + 4, _mm_unpackhi_ps(u, v));  // u2 v2 u3 v3
    } else {
        const __m128 x = load(0), y = load(1), z = load(2);
        const __m128 xy_lo = _mm_unpacklo_ps(x, y);  // x0 y0 x1 y1
        const __m128 xy_hi = _mm_unpackhi_ps(x, y);  // x2 y2 x3 y3
        const __m128 z0z0x1x1 = _mm_shuffle_ps(z, x, _MM_SHUFFLE(1, 1, 0, 0));
        const __m128 y1y1z1z1 = _mm_shuffle_ps(y, z, _MM_SHUFFLE(1, 1, 1, 1));
        const __m128 z2z3x3y3 = _mm_shuffle_ps(z, xy_hi, _MM_SHUFFLE(3, 2, 3, 2));
        _mm_stream_ps(out, _mm_shuffle_ps(xy_lo, z0z0x1x1, _MM_SHUFFLE(2, 0, 1, 0)));         // x0 y0 z0 x1
        _mm_stream_ps(out + 4, _mm_shuffle_ps(y1y1z1z1, xy_hi, _MM_SHUFFLE(1, 0, 2, 0)));     // y1 z1 x2 y2
        _mm_stream_ps(out + 8, _mm_shuffle_ps(z2z3x3y3, z2z3x3y3, _MM_SHUFFLE(1, 3, 2, 0)));  // z2 x3 y3 z3
    }
}
#endif

// Tile row y into `row` (the image row's first pixel of the tile), C channels, masked by `hits`
// when Masked.
template <int C, bool Masked>
void stream_row(const TilePixelLanes& tile, const float* const* planes, const float* hits, int y,
                float* row) {
#if defined(__SSE2__)
    // Every 4-aligned run then starts 16-byte aligned too (4 pixels of C floats).
    const bool aligned = (reinterpret_cast<std::uintptr_t>(row) & 15u) == 0;
#endif
    for (int x = 0; x < tile.width(); x += 4) {
#if defined(__SSE2__)
        const int lane = tile.run_of_four(x, y);
        if (aligned && lane >= 0) {
            stream_four<C, Masked>(planes, hits, lane, row + std::size_t(x) * C);
            continue;
        }
#endif
        for (int px = x; px < std::min(x + 4, tile.width()); ++px) {
            const int l = tile.lane(px, y);
            const bool keep = !Masked || hits[l] > 0.f;
            // Copied as bits: a plane may hold integers (GBuffer::triangle).
            for (int k = 0; k < C; ++k) {
                float* to = row + std::size_t(px) * C + std::size_t(k);
                if (keep)
                    std::memcpy(to, planes[k] + l, sizeof(float));
                else
                    *to = 0.f;
            }
        }
    }
}

template <int C>
void stream_rows(const TilePixelLanes& tile, const float* const* planes, const float* hits, float* image,
                 int image_width, int x0, int y0) {
    for (int y = 0; y < tile.height(); ++y) {
        float* row = image + (std::size_t(y0 + y) * std::size_t(image_width) + std::size_t(x0)) * C;
        if (hits)
            stream_row<C, true>(tile, planes, hits, y, row);
        else
            stream_row<C, false>(tile, planes, hits, y, row);
    }
}

}  // namespace

void stream_lanes(const TilePixelLanes& tile, const float* const* planes, int channels, const float* hits,
                  float* image, int image_width, int x0, int y0) {
    switch (channels) {
        case 1:
            return stream_rows<1>(tile, planes, hits, image, image_width, x0, y0);
        case 2:
            return stream_rows<2>(tile, planes, hits, image, image_width, x0, y0);
        case 3:
            return stream_rows<3>(tile, planes, hits, image, image_width, x0, y0);
        default:
            TDF_CHECK(channels >= 1 && channels <= 3);
    }
}

void stream_gbuffer_tile(const TilePixelLanes& tile, const GBufferLanes& lanes, GBuffer& out, int x0,
                         int y0) {
    static_assert(sizeof(Vec2f) == 2 * sizeof(float) && sizeof(Vec3f) == 3 * sizeof(float), "packed pixels");
    const auto put = [&](auto* image, std::initializer_list<const float*> planes) {
        float* const pixels = reinterpret_cast<float*>(image);
        stream_lanes(tile, planes.begin(), int(planes.size()), nullptr, pixels, out.width, x0, y0);
    };
    put(out.mask.data(), {lanes.mask});
    if (out.has_ids_and_depth()) {
        // The ids go through as bits (stream_lanes copies words).
        put(out.triangle.data(), {reinterpret_cast<const float*>(lanes.triangle)});
        put(out.barycentric.data(), {lanes.b1, lanes.b2});
        put(out.depth.data(), {lanes.depth});
    }
    put(out.position.data(), {lanes.qx, lanes.qy, lanes.qz});
    put(out.normal.data(), {lanes.nx, lanes.ny, lanes.nz});
    put(out.tangent.data(), {lanes.tx, lanes.ty, lanes.tz});
    put(out.handedness.data(), {lanes.w});
    put(out.uv.data(), {lanes.u, lanes.v});
    put(out.duv_dx.data(), {lanes.du_dx, lanes.dv_dx});
    put(out.duv_dy.data(), {lanes.du_dy, lanes.dv_dy});
}

void streaming_fence() {
#if defined(__SSE2__)
    _mm_sfence();
#endif
}

}  // namespace tdf
