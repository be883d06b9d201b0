// Issue 29's spot strips: the darkest and brightest one-chart window of the input, and the strip
// input | after matching | final built from the three maps' crops there (a run keeps only the
// after-matching crops through the refinement, not the whole map).
#include <tdf/train/albedo_spots.h>

#include <gtest/gtest.h>

namespace tdf {
namespace {

Image gradient_map(int size, float offset) {
    Image map(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            for (int c = 0; c < 3; ++c) map.at(x, y, c) = offset + 0.01f * float(x) + 0.001f * float(y) + 0.1f * float(c);
    return map;
}

TEST(AlbedoSpots, FindsTheDarkestAndBrightestOneChartWindow) {
    const int size = 32;
    const Image input = gradient_map(size, 0.0f);
    std::vector<int> label(input.pixel_count(), 0);
    for (int y = 0; y < size; ++y) label[std::size_t(y) * size + size - 1] = 1;  // a second chart on the last column
    const std::vector<AlbedoSpot> spots = find_albedo_spots(input, label, 8);
    ASSERT_EQ(spots.size(), 2u);
    EXPECT_EQ(spots[0].name, "dark");
    EXPECT_EQ(spots[0].x, 0);
    EXPECT_EQ(spots[0].y, 0);
    EXPECT_EQ(spots[1].name, "bright");
    EXPECT_EQ(spots[1].x, 22);  // the last window on the grid of 2 that stays off the second chart
    EXPECT_EQ(spots[1].y, 24);
    EXPECT_LT(spots[0].luminance, spots[1].luminance);
}

TEST(AlbedoSpots, StripShowsTheThreeCropsZoomedAndClamped) {
    const AlbedoSpot spot{"dark", 3, 5, 4, 0.0};
    const Image input = gradient_map(16, 0.0f), matched = gradient_map(16, 0.5f), final_albedo = gradient_map(16, 0.95f);
    const Image crop = albedo_spot_crop(spot, matched);
    ASSERT_EQ(crop.width(), 4);
    ASSERT_EQ(crop.height(), 4);
    EXPECT_EQ(crop.at(1, 2, 1), matched.at(4, 7, 1));
    const int zoom = 3, side = 4 * zoom, gap = 4;
    const Image strip =
        albedo_spot_strip(albedo_spot_crop(spot, input), crop, albedo_spot_crop(spot, final_albedo), zoom);
    ASSERT_EQ(strip.width(), 3 * side + 2 * gap);
    ASSERT_EQ(strip.height(), side);
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x)
            for (int c = 0; c < 3; ++c) {
                const int u = spot.x + x / zoom, v = spot.y + y / zoom;
                EXPECT_EQ(strip.at(x, y, c), input.at(u, v, c));
                EXPECT_EQ(strip.at(side + gap + x, y, c), matched.at(u, v, c));
                EXPECT_EQ(strip.at(2 * (side + gap) + x, y, c), std::min(final_albedo.at(u, v, c), 1.0f));
            }
    for (int y = 0; y < side; ++y) EXPECT_EQ(strip.at(side + 1, y, 0), 1.0f);  // the white gap
    EXPECT_GT(final_albedo.at(spot.x + 3, spot.y + 3, 2), 1.0f);  // so the clamp above was exercised
}

}  // namespace
}  // namespace tdf
