// Ambient occlusion from heights (issue 24's optional derived map): known answers on a flat map
// and a ramp, tileability, and charts that do not shade each other.
#include <gtest/gtest.h>
#include <tdf/tactile/ambient_occlusion.h>

#include <cmath>

using namespace tdf;

TEST(AmbientOcclusion, FlatReliefSeesTheWholeSky) {
    Image flat(40, 30, 1);
    for (float& v : flat.values()) v = 0.25f;
    const Image ao = ambient_occlusion(flat, 0.1f, false);
    for (float v : ao.values()) EXPECT_EQ(v, 1.0f);
}

TEST(AmbientOcclusion, RampHidesTheSkyByTheKnownHorizon) {
    // h = a x: looking uphill (+x) the horizon rises at tan = a, on the two 45-degree diagonals
    // uphill at a cos 45; downhill and across it stays at 0.
    const int size = 64;
    const float texel = 0.05f, a = 0.7f;
    Image ramp(size, size, 1);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) ramp.at(x, y, 0) = a * texel * float(x);
    const Image ao = ambient_occlusion(ramp, texel, false);
    const auto sine = [](double t) { return t / std::sqrt(1 + t * t); };
    const double expected = 1.0 - (sine(a) + 2 * sine(a / std::sqrt(2.0))) / kAoDirections;
    // Away from the borders (a march reaches kAoRadiusTexels without leaving the map).
    for (int y = 20; y < 44; ++y)
        for (int x = 0; x < 44; ++x) EXPECT_NEAR(ao.at(x, y, 0), expected, 1e-5) << x << "," << y;
}

TEST(AmbientOcclusion, TileableHeightsGiveTileableOcclusion) {
    const int size = 48;
    Image h(size, size, 1), shifted(size, size, 1);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            h.at(x, y, 0) = float(std::sin(6.283185307 * x / 16.0) * std::cos(6.283185307 * y / 12.0));
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) shifted.at(x, y, 0) = h.at((x + 7) % size, (y + 5) % size, 0);
    const Image a = ambient_occlusion(h, 0.2f, true), b = ambient_occlusion(shifted, 0.2f, true);
    float darkest = 1.0f;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            EXPECT_EQ(b.at(x, y, 0), a.at((x + 7) % size, (y + 5) % size, 0));
            darkest = std::min(darkest, a.at(x, y, 0));
        }
    EXPECT_LT(darkest, 0.9f);  // the troughs are shaded
}

TEST(AmbientOcclusion, AChartIsNotShadedByItsNeighbourInTheAtlas) {
    // A tall block on the right half belongs to another chart: the left half stays open.
    const int size = 40;
    Image h(size, size, 1);
    std::vector<int> region(h.pixel_count());
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            h.at(x, y, 0) = x < 20 ? 0.0f : 5.0f;
            region[std::size_t(y * size + x)] = x < 20 ? 0 : 1;
        }
    const Image charts = ambient_occlusion(h, 0.1f, false, region), one = ambient_occlusion(h, 0.1f, false);
    EXPECT_EQ(charts.at(19, 20, 0), 1.0f);
    EXPECT_LT(one.at(19, 20, 0), 0.9f);  // without the regions the block would shade it
}
