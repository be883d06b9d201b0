#include <tdf/tactile/relief_statistics.h>

#include <gtest/gtest.h>

#include <cmath>

namespace tdf {
namespace {

Vec3f tilted(float degrees_from_z, float azimuth) {
    const float t = degrees_from_z * kPi / 180.0f;
    return {std::sin(t) * std::cos(azimuth), std::sin(t) * std::sin(azimuth), std::cos(t)};
}

TEST(TactileReliefStatistics, TiltHistogramBinsByAngleFromZ) {
    // 16 bins of 3.75 degrees over [0, 60]: 1 -> bin 0, 10 -> bin 2, 59 -> bin 15, 80 -> bin 15.
    const std::vector<Vec3f> normals = {tilted(1, 0.3f), tilted(10, 2.0f), tilted(10, -1.0f), tilted(59, 0),
                                        tilted(80, 1), Vec3f(0, 0, 0)};
    const std::vector<double> h = tilt_histogram(normals.data(), normals.size());
    ASSERT_EQ(h.size(), 16u);
    EXPECT_DOUBLE_EQ(h[0], 0.2);  // the zero vector is skipped: five count
    EXPECT_DOUBLE_EQ(h[2], 0.4);
    EXPECT_DOUBLE_EQ(h[15], 0.4);
    // Unnormalised vectors count by direction.
    const Vec3f scaled = tilted(10, 0) * 3.0f;
    EXPECT_DOUBLE_EQ(tilt_histogram(&scaled, 1)[2], 1.0);
    // The image overload reads the first three channels.
    Image image(2, 1, 4, 0.0f);
    image.at(0, 0, 2) = 1.0f;
    image.at(1, 0, 0) = 1.0f;  // 90 degrees: last bin
    const std::vector<double> hi = tilt_histogram(image);
    EXPECT_DOUBLE_EQ(hi[0], 0.5);
    EXPECT_DOUBLE_EQ(hi[15], 0.5);
}

TEST(TactileReliefStatistics, HistogramDistanceIsL1) {
    EXPECT_DOUBLE_EQ(histogram_l1_distance({0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}), 0.0);
    EXPECT_DOUBLE_EQ(histogram_l1_distance({1.0, 0.0}, {0.0, 1.0}), 2.0);
    EXPECT_DOUBLE_EQ(histogram_l1_distance({0.75, 0.25}, {0.5, 0.5}), 0.5);
    const std::vector<double> empty = tilt_histogram(nullptr, 0);
    EXPECT_DOUBLE_EQ(histogram_l1_distance(empty, std::vector<double>(16, 0.0)), 0.0);
}

}  // namespace
}  // namespace tdf
