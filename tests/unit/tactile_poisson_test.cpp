#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/tactile/poisson.h>

#include <cmath>

using namespace tdf;

namespace {

constexpr double kPi = 3.14159265358979323846;

// RMS of (a - b) after removing the mean difference (heights are defined up to a constant).
double rms_difference(const Image& a, const Image& b) {
    double mean = 0;
    for (std::size_t i = 0; i < a.values().size(); ++i) mean += double(a.values()[i]) - b.values()[i];
    mean /= double(a.values().size());
    double sum = 0;
    for (std::size_t i = 0; i < a.values().size(); ++i) {
        const double d = double(a.values()[i]) - b.values()[i] - mean;
        sum += d * d;
    }
    return std::sqrt(sum / double(a.values().size()));
}

// h(x, y) = sin(2 pi x / w) cos(3 pi y / h) * amplitude + 0.3 x, with its exact derivatives at
// pixel centres (x = column, y = row), so the test knows the true gradients.
void smooth_field(int n, Image& height, Image& gx, Image& gy) {
    height = Image(n, n, 1), gx = Image(n, n, 1), gy = Image(n, n, 1);
    const double amplitude = double(n) / 8.0;  // slopes of order 1 at every resolution
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double a = 2 * kPi * x / n, b = 3 * kPi * y / n;
            height.at(x, y, 0) = float(amplitude * std::sin(a) * std::cos(b) + 0.3 * x);
            gx.at(x, y, 0) = float(amplitude * 2 * kPi / n * std::cos(a) * std::cos(b) + 0.3);
            gy.at(x, y, 0) = float(-amplitude * 3 * kPi / n * std::sin(a) * std::sin(b));
        }
}

}  // namespace

TEST(Poisson, RecoversALinearRampExactly) {
    Image gx(37, 23, 1, 0.25f), gy(37, 23, 1, -0.5f), ramp(37, 23, 1);
    for (int y = 0; y < 23; ++y)
        for (int x = 0; x < 37; ++x) ramp.at(x, y, 0) = 0.25f * x - 0.5f * y;
    const Image h = integrate_gradients(gx, gy);
    EXPECT_LT(rms_difference(h, ramp), 1e-5);  // rounding only
}

TEST(Poisson, SmoothFieldErrorIsSecondOrder) {
    // Error bound: RMS error below 0.2% of the field's amplitude (n/8) at n = 128, and the
    // error falls by about 4x when the resolution doubles (trapezoid + 5-point Laplacian).
    double errors[2];
    for (int k = 0; k < 2; ++k) {
        const int n = 64 << k;
        Image height, gx, gy;
        smooth_field(n, height, gx, gy);
        errors[k] = rms_difference(integrate_gradients(gx, gy), height) / (n / 8.0);
    }
    RecordProperty("relative_rms_64", std::to_string(errors[0]));
    RecordProperty("relative_rms_128", std::to_string(errors[1]));
    EXPECT_LT(errors[1], 2e-3);
    EXPECT_GT(errors[0] / errors[1], 3.0);
    EXPECT_LT(errors[0] / errors[1], 5.0);
}

TEST(Poisson, CentralDifferencesOfAHeightIntegrateBackClosely) {
    Image height, gx, gy;
    smooth_field(96, height, gx, gy);
    Image cx, cy;
    height_gradients(height, cx, cy);
    EXPECT_LT(rms_difference(integrate_gradients(cx, cy), height) / (96 / 8.0), 5e-3);
}

TEST(Poisson, RejectsBadGradients) {
    Image gx(8, 8, 1), gy(8, 7, 1);
    EXPECT_THROW(integrate_gradients(gx, gy, "g.npz"), Error);
    Image nan(8, 8, 1);
    nan.at(3, 3, 0) = std::nanf("");
    try {
        integrate_gradients(nan, gx, "g.npz");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("g.npz"), std::string::npos);
    }
}
