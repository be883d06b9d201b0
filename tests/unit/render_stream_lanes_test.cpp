#include <gtest/gtest.h>
#include <tdf/render/stream_lanes.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

using namespace tdf;

namespace {

// A w x h tile's lanes in the tracer's packet order: packets of 4 x packet_height pixels, row by
// row of packets; lanes of a packet that stick out of the tile get pixel -1. packet_height 0
// gives the row-major order GBufferLanes::assign gives.
std::unique_ptr<GBufferLanes> lanes_in_packets(int w, int h, int packet_height) {
    auto g = std::make_unique<GBufferLanes>();
    g->width = w, g->height = h, g->count = 0;
    if (packet_height == 0) {
        for (int i = 0; i < w * h; ++i) g->pixel[g->count++] = i;
        return g;
    }
    for (int by = 0; by < h; by += packet_height)
        for (int bx = 0; bx < w; bx += 4)
            for (int lane = 0; lane < 4 * packet_height; ++lane) {
                const int x = bx + lane % 4, y = by + lane / 4;
                g->pixel[g->count++] = x < w && y < h ? y * w + x : -1;
            }
    return g;
}

// One call of stream_lanes on a fresh image against the plain loop it stands for.
struct StreamCase {
    int packet_height;  // lanes_in_packets
    int image_width;
    bool at_left;  // the tile at the image's left edge, or near its right one
    int offset;    // the image's first float, in floats from a 64-byte boundary
    int w, h;      // the tile
    int channels;
    bool masked;  // with the hit mask
};

::testing::AssertionResult streams_like_the_plain_loop(const StreamCase& c) {
    const auto g = lanes_in_packets(c.w, c.h, c.packet_height);
    // Lane values that tell lane and channel apart, and some that are not numbers (a masked
    // lane must come out as +0, NaN or not).
    std::vector<float> planes(3 * GBufferLanes::kMax), hits(GBufferLanes::kMax);
    for (int i = 0; i < GBufferLanes::kMax; ++i) {
        for (int k = 0; k < 3; ++k) planes[k * GBufferLanes::kMax + i] = i % 11 == 5 ? NAN : 1000.f * k + i;
        hits[i] = i % 3 == 0 ? 0.f : (i % 7 == 0 ? -1.f : 1.f);
    }
    const float* plane_of[3] = {&planes[0], &planes[GBufferLanes::kMax], &planes[2 * GBufferLanes::kMax]};
    const int image_height = 9, x0 = c.at_left ? 0 : c.image_width - c.w - 2, y0 = 8 - c.h;
    const std::size_t size = std::size_t(c.image_width) * image_height * std::size_t(c.channels);
    std::vector<float> buffer(size + 32, -7.f), expected(size, -7.f);
    float* image = buffer.data();
    while (reinterpret_cast<std::uintptr_t>(image) % 64 != 0) ++image;
    image += c.offset;
    std::fill(image, image + size, -7.f);
    for (int i = 0; i < g->count; ++i) {
        if (g->pixel[i] < 0) continue;
        const int x = x0 + g->pixel[i] % c.w, y = y0 + g->pixel[i] / c.w;
        for (int k = 0; k < c.channels; ++k)
            expected[(std::size_t(y) * std::size_t(c.image_width) + std::size_t(x)) *
                         std::size_t(c.channels) +
                     std::size_t(k)] = c.masked && !(hits[i] > 0.f) ? 0.f : plane_of[k][i];
    }
    TilePixelLanes tile;
    tile.build(*g);
    stream_lanes(tile, plane_of, c.channels, c.masked ? hits.data() : nullptr, image, c.image_width, x0, y0);
    streaming_fence();
    if (std::memcmp(image, expected.data(), size * sizeof(float)) == 0) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure()
           << "packets 4x" << c.packet_height << ", image width " << c.image_width << ", x0 " << x0
           << ", offset " << c.offset << ", tile " << c.w << "x" << c.h << ", " << c.channels
           << " channels, masked " << c.masked;
}

}  // namespace

// stream_lanes against the plain loop it stands for, bit for bit, in every layout the renderer
// meets: 16- and 8-lane packets and row-major lanes, full tiles and tiles cut by the image's edge
// (packets sticking out), image rows 16-byte aligned (streaming stores) or not (plain stores), 1
// to 3 channels, with and without the hit mask. Pixels outside the tile stay untouched.
TEST(StreamLanes, WritesEachLaneToItsPixelBitForBit) {
    int cases = 0;
    for (int packet_height : {4, 2, 0})
        for (int image_width : {128, 67})
            for (bool at_left : {true, false})
                for (int offset : {0, 4, 1})
                    for (int w : {64, 7, 3})
                        for (int h : {4, 3})
                            for (int channels = 1; channels <= 3; ++channels)
                                for (bool masked : {false, true}) {
                                    ASSERT_TRUE(streams_like_the_plain_loop({packet_height,
                                                                             image_width,
                                                                             at_left,
                                                                             offset,
                                                                             w,
                                                                             h,
                                                                             channels,
                                                                             masked}));
                                    ++cases;
                                }
    EXPECT_EQ(cases, 3 * 2 * 2 * 3 * 3 * 2 * 3 * 2);
}

// The runs of four that go out as vectors: every 4-aligned run of a full packet row, none that
// reaches past the tile's width.
TEST(StreamLanes, RunsOfFourAreThePacketRows) {
    const auto full = lanes_in_packets(64, 4, 4);
    TilePixelLanes tile;
    tile.build(*full);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 64; x += 4) {
            EXPECT_EQ(tile.lane(x, y), (x / 4) * 16 + y * 4);
            EXPECT_EQ(tile.run_of_four(x, y), tile.lane(x, y)) << x << ", " << y;
        }
    // 7x3 in 4x2 packets: two packets a packet row, the second one sticking out by a pixel.
    const auto cut = lanes_in_packets(7, 3, 2);
    tile.build(*cut);
    EXPECT_EQ(tile.run_of_four(0, 2), 2 * 8);  // second packet row, its first packet, lane 0
    EXPECT_EQ(tile.lane(4, 2), 2 * 8 + 8);     // ... its second packet, lane 0
    EXPECT_EQ(tile.run_of_four(4, 0), -1);     // pixels 4..6 only
    EXPECT_EQ(tile.run_of_four(4, 2), -1);
}
