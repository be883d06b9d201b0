#pragma once
/// Writing a tile's lanes into full-size images. The renderer computes each pass of a tile in
/// lanes (one plane a channel, lanes in packet order: gbuffer_lanes.h) and writes them straight
/// into the frame's interleaved images, one image row at a time, left to right, so that each
/// cache line is written whole before the next, with streaming stores: the frame is not read
/// again while it is rendered, and a line written whole needs no read from memory first.
#include <tdf/render/gbuffer_lanes.h>

namespace tdf {

/// Which lane each pixel of a tile is (the inverse of GBufferLanes::pixel), worked out once a
/// tile for all its passes.
class TilePixelLanes {
public:
    void build(const GBufferLanes& lanes);
    int width() const { return m_width; }
    int height() const { return m_height; }
    /// The lane of tile pixel (x, y).
    int lane(int x, int y) const { return m_lane[y * m_width + x]; }
    /// For x a multiple of 4: lane(x, y) if pixels (x .. x + 3, y) are inside the tile and are the
    /// lanes lane(x, y) .. lane(x, y) + 3 (packets are 4 pixels wide, so every 4-aligned run of a
    /// full packet row is), else -1.
    int run_of_four(int x, int y) const { return m_run[y * m_runs_per_row + x / 4]; }

private:
    int m_width = 0, m_height = 0, m_runs_per_row = 0;
    int m_lane[GBufferLanes::kMax];
    int m_run[GBufferLanes::kMax];  // ceil(width / 4) a row: at most width x height
};

/// Writes `channels` (1 to 3) planes of lane values into the tile's pixels of an interleaved
/// image `image_width` pixels wide, the tile's pixel (0, 0) at image pixel (x0, y0): channel k of
/// the pixel of lane i is planes[k][i]. With `hits`, lanes whose hits[i] is not > 0 are written
/// as zeros. Runs of four lanes go out as vectors of streaming stores where the image row is
/// 16-byte aligned; the rest with plain stores. Call streaming_fence() before another thread
/// reads the image.
void stream_lanes(const TilePixelLanes& tile, const float* const* planes, int channels, const float* hits,
                  float* image, int image_width, int x0, int y0);

/// Writes every field `out` holds (out.fields) of a traced tile into `out`'s full-frame arrays,
/// the tile's pixel (0, 0) at (x0, y0), with stream_lanes: the full-frame G-buffer the trainer and
/// the evaluation read, written a cache line at a time. `tile` is built from `lanes`.
void stream_gbuffer_tile(const TilePixelLanes& tile, const GBufferLanes& lanes, GBuffer& out, int x0, int y0);

/// Orders the streaming stores before any later store (they are weakly ordered).
void streaming_fence();

}  // namespace tdf
