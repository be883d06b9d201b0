// Issue 24: the virtual GelSight measures what an asset's relief is, at physical scale.
#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/render/virtual_gelsight.h>
#include <tdf/tactile/height_map.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/touch_comparison.h>

#include <cmath>
#include <filesystem>

#include "common/test_paths.h"
#include "unit/gelsight_plate.h"

using namespace tdf;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Up-crossings of the row's mean (linear interpolation), in pixels.
std::vector<double> up_crossings(const std::vector<double>& row) {
    double mean = 0;
    for (double v : row) mean += v / double(row.size());
    std::vector<double> at;
    for (std::size_t i = 0; i + 1 < row.size(); ++i) {
        const double a = row[i] - mean, b = row[i + 1] - mean;
        if (a < 0 && b >= 0) at.push_back(double(i) + a / (a - b));
    }
    return at;
}

// Amplitude of the sinusoid of period `period_px` in `row` (least squares on sin, cos, 1).
double fitted_amplitude(const std::vector<double>& row, double period_px) {
    double m[3][4] = {};
    for (std::size_t i = 0; i < row.size(); ++i) {
        const double w = 2 * kPi * double(i) / period_px, f[3] = {std::sin(w), std::cos(w), 1.0};
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) m[r][c] += f[r] * f[c];
            m[r][3] += f[r] * row[i];
        }
    }
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
            if (r != c) {
                const double k = m[r][c] / m[c][c];
                for (int j = c; j < 4; ++j) m[r][j] -= k * m[c][j];
            }
    const double a = m[0][3] / m[0][0], b = m[1][3] / m[1][1];
    return std::sqrt(a * a + b * b);
}

}  // namespace

// The known answer: a plate with a 0.05 mm, 2 mm sinusoid simulates back to the same amplitude
// and wavelength within 2 % (every row of the pad, the wavelength from the first to the last
// up-crossing, the amplitude fitted at that wavelength).
TEST(VirtualGelSight, PlateWithSinusoidSimulatesBackToItsAmplitudeAndWavelength) {
    const std::string folder = test::scratch_dir() + "/gelsight_plate";
    const double amplitude = 0.05, wavelength = 2.0;
    test::write_plate(folder, 20.0f, amplitude, wavelength);
    const auto asset = load_relief_asset(folder);
    EXPECT_NEAR(asset->mm_per_unit, 20.0f, 20.0f * 1e-4f);
    const std::optional<TouchPoint> point = touch_point_at_uv(asset->mesh, {0.5f, 0.5f});
    ASSERT_TRUE(point.has_value());
    EXPECT_NEAR(point->normal.z, 1.0f, 1e-5f);
    GelSightPad pad;
    pad.width = pad.height = 120;  // 10.2 mm: five periods
    const SimulatedTouch touch = simulate_touch(*asset, *point, pad);
    ASSERT_EQ(touch.height.height.width(), 120);
    EXPECT_FLOAT_EQ(touch.height.mm_per_pixel, pad.mm_per_pixel);
    double worst_wavelength = 0, worst_amplitude = 0;
    for (int y = 0; y < pad.height; ++y) {
        std::vector<double> row(std::size_t(pad.width), 0.0);
        for (int x = 0; x < pad.width; ++x) row[std::size_t(x)] = touch.height.height.at(x, y, 0);
        const std::vector<double> ups = up_crossings(row);
        ASSERT_GE(ups.size(), 4u) << "row " << y;
        const double period_px = (ups.back() - ups.front()) / double(ups.size() - 1);
        const double measured_wavelength = period_px * pad.mm_per_pixel;
        const double measured_amplitude = fitted_amplitude(row, period_px);
        worst_wavelength = std::max(worst_wavelength, std::abs(measured_wavelength / wavelength - 1));
        worst_amplitude = std::max(worst_amplitude, std::abs(measured_amplitude / amplitude - 1));
    }
    std::printf("worst row: wavelength off by %.3f %%, amplitude by %.3f %%\n", 100 * worst_wavelength,
                100 * worst_amplitude);
    EXPECT_LT(worst_wavelength, 0.02);
    EXPECT_LT(worst_amplitude, 0.02);
    // The preview is grey where the gel is flat and coloured on slopes.
    float spread = 0;
    for (float v : touch.preview.values()) spread = std::max(spread, std::abs(v - 0.5f));
    EXPECT_GT(spread, 0.05f);
}

// Bad input: a UV point no face covers, a pad larger than the part, a folder without an asset.
TEST(VirtualGelSight, BadInputIsAClearError) {
    const std::string folder = test::scratch_dir() + "/gelsight_bad";
    test::write_plate(folder, 20.0f, 0.05, 2.0);
    const auto asset = load_relief_asset(folder);
    EXPECT_FALSE(touch_point_at_uv(asset->mesh, {1.5f, 0.5f}).has_value());
    GelSightPad pad;
    pad.width = pad.height = 300;  // 25.5 mm on a 20 mm plate
    try {
        simulate_touch(*asset, *touch_point_at_uv(asset->mesh, {0.5f, 0.5f}), pad);
        FAIL() << "a pad larger than the plate was pressed";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("larger than the part"), std::string::npos) << e.what();
    }
    const std::string empty = test::scratch_dir() + "/gelsight_empty";
    std::filesystem::create_directories(empty);
    try {
        load_relief_asset(empty);
        FAIL() << "a folder without an asset loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no asset with a height map"), std::string::npos) << e.what();
    }
}

// Random touch points are reproducible and lie on the surface.
TEST(VirtualGelSight, RandomPointsAreSeededAndOnTheSurface) {
    const std::string folder = test::scratch_dir() + "/gelsight_points";
    test::write_plate(folder, 20.0f, 0.05, 2.0);
    const auto asset = load_relief_asset(folder);
    const auto a = random_touch_points(asset->mesh, 16, 7), b = random_touch_points(asset->mesh, 16, 7);
    ASSERT_EQ(a.size(), 16u);
    for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_EQ(a[k].position.x, b[k].position.x);
        EXPECT_NEAR(a[k].position.z, 0.0f, 1e-6f);
        EXPECT_NEAR(a[k].uv.x, a[k].position.x, 1e-5f);  // the plate's UV is its xy
        EXPECT_NEAR(a[k].uv.y, a[k].position.y, 1e-5f);
    }
}

// The round trip compares touches with the whole capture, as the asset carries the whole map:
// a sparse relief (bumps on a flat) measured only where it is textured would look rougher than
// random touches of the asset can ever feel. With bumps everywhere the two areas agree.
TEST(VirtualGelSight, CaptureIsComparedOverWhatTheAssetCarries) {
    const int size = 128;
    const auto bumps = [&](bool left_half_only) {
        Image height(size, size, 1);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                if (left_half_only && x >= size / 2) continue;
                const double cx = std::fmod(x, 16.0) - 8.0, cy = std::fmod(y, 16.0) - 8.0;
                height.at(x, y, 0) = float(3.0 * std::exp(-(cx * cx + cy * cy) / 8.0));
            }
        return normals_from_height(height, 1.0f);
    };
    const Image sparse = bumps(true), dense = bumps(false);
    const ReliefMeasure sparse_whole = measure_capture(sparse, 0.1f, 32, CaptureArea::Whole);
    const ReliefMeasure sparse_contact = measure_capture(sparse, 0.1f, 32, CaptureArea::Contact);
    const ReliefMeasure dense_whole = measure_capture(dense, 0.1f, 32, CaptureArea::Whole);
    const ReliefMeasure dense_contact = measure_capture(dense, 0.1f, 32, CaptureArea::Contact);
    std::printf("detail tilt: sparse %.2f whole / %.2f contact, dense %.2f / %.2f deg\n", sparse_whole.detail_tilt,
                sparse_contact.detail_tilt, dense_whole.detail_tilt, dense_contact.detail_tilt);
    EXPECT_LT(sparse_whole.detail_tilt, 0.75 * sparse_contact.detail_tilt);
    EXPECT_NEAR(sparse_whole.detail_tilt / dense_whole.detail_tilt, 0.5, 0.1);  // half the map has bumps
    EXPECT_NEAR(dense_whole.detail_tilt / dense_contact.detail_tilt, 1.0, 0.1);
}
