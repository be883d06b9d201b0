// Issue 24: the height map written beside an exported normal map reproduces it.
#include <gtest/gtest.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/height_export.h>
#include <tdf/tactile/height_input.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/tactile/normal_map.h>

#include <cmath>
#include <filesystem>

#include "common/test_paths.h"
#include "tactile_test_util.h"

using namespace tdf;

namespace {

double rms(const Image& a) {
    double s = 0;
    for (float v : a.values()) s += double(v) * v;
    return std::sqrt(s / double(a.values().size()));
}

// RMS of a - b (both zero mean) over the RMS of b.
double relative_rms_error(const Image& a, const Image& b) {
    double s = 0;
    for (std::size_t i = 0; i < a.values().size(); ++i) {
        const double d = double(a.values()[i]) - b.values()[i];
        s += d * d;
    }
    return std::sqrt(s / double(a.values().size())) / rms(b);
}

Image zero_mean(Image h) {
    double mean = 0;
    for (float v : h.values()) mean += v;
    mean /= double(h.values().size());
    for (float& v : h.values()) v = float(v - mean);
    return h;
}

}  // namespace

// A periodic height (a whole number of waves) comes back exactly from its central-difference
// normals: the integration inverts normals_from_height up to the mean.
TEST(HeightExport, PeriodicHeightComesBackFromItsNormals) {
    const int n = 64;
    Image h(n, n, 1);
    const double pi = 3.14159265358979323846;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            h.at(x, y, 0) = float(2.0 * std::sin(2 * pi * 3 * x / n) * std::cos(2 * pi * 5 * y / n) +
                                  1.5 * std::cos(2 * pi * (4 * x + 7 * y) / n));
    const Image back = integrate_normal_map(normals_from_height(h, 1.0f, true), true);
    const double error = relative_rms_error(back, zero_mean(h));
    EXPECT_LT(error, 1e-4) << "relative RMS error " << error;
}

// A non-periodic map (a ramp plus waves that do not close) is integrated on its mirror image:
// the interior slopes and so the normals come back, the borders do not wrap.
TEST(HeightExport, NonPeriodicMapKeepsItsNormals) {
    const int n = 80;
    Image h(n, n, 1);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            h.at(x, y, 0) = float(0.05 * x - 0.02 * y + 0.8 * std::sin(0.37 * x + 0.11 * y) + 0.3 * std::cos(0.21 * y));
    const Image normals = normals_from_height(h, 1.0f, false);
    const Image back = integrate_normal_map(normals, false);
    const double cosine = height_normal_consistency(back, 1.0f, normals, false);
    EXPECT_GT(cosine, 0.9999) << "mean cosine " << cosine;
    // The heights themselves: measured 3.0 % RMS error, from the border texels, whose normals
    // copy the nearest interior slope (normals_from_height) and so do not say the border's own.
    EXPECT_LT(relative_rms_error(back, zero_mean(h)), 0.04);
}

// The mirrored integration (one DCT pair on the map) is the periodic integration of the map
// mirrored to twice its size (even heights, odd slopes), restricted to the map: the same least
// squares, solved in a quarter of the memory. Odd sizes and a non-square map included.
TEST(HeightExport, MirroredIntegrationEqualsThePeriodicSolutionOfTheMirror) {
    for (const auto& [w, h] : {std::pair{37, 23}, std::pair{64, 64}}) {
        const Image normals = normals_from_height(test::synthetic_texture(std::max(w, h), 5), 0.7f, false);
        Image map(w, h, 3), mirror(2 * w, 2 * h, 3);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) map.at(x, y, c) = normals.at(x, y, c);
        for (int Y = 0; Y < 2 * h; ++Y)
            for (int X = 0; X < 2 * w; ++X) {
                const int x = X < w ? X : 2 * w - 1 - X, y = Y < h ? Y : 2 * h - 1 - Y;
                mirror.at(X, Y, 0) = (X < w ? 1.0f : -1.0f) * map.at(x, y, 0);
                mirror.at(X, Y, 1) = (Y < h ? 1.0f : -1.0f) * map.at(x, y, 1);
                mirror.at(X, Y, 2) = map.at(x, y, 2);
            }
        const Image dct = integrate_normal_map(map, false), fft = integrate_normal_map(mirror, true);
        double worst = 0, range = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                worst = std::max(worst, double(std::abs(dct.at(x, y, 0) - fft.at(x, y, 0))));
                range = std::max(range, double(std::abs(fft.at(x, y, 0))));
            }
        EXPECT_GT(range, 0.1) << w << "x" << h;
        EXPECT_LT(worst, 1e-5 * range) << w << "x" << h << ": largest difference " << worst;
    }
}

// Scale: heights in mm are the integrated slopes times the texel size, so the same normals at
// twice the texel size give twice the heights; the JSON says how to restore mm from the PNG.
TEST(HeightExport, HeightsScaleWithTheTexelSize) {
    const Image normals = normals_from_height(test::synthetic_texture(48, 3), 0.5f, true);
    ExportScale scale;
    scale.periodic = true;
    scale.mm_per_texel = 0.05f;
    scale.mm_per_unit = 100.0f;
    const ExportedHeight a = export_height(normals, scale, "a");
    scale.mm_per_texel = 0.1f;
    const ExportedHeight b = export_height(normals, scale, "b");
    EXPECT_NEAR(rms(b.map.height) / rms(a.map.height), 2.0, 1e-4);
    EXPECT_GT(a.mean_cosine, 0.9999);
    EXPECT_GT(b.mean_cosine, 0.9999);
    const Json j = exported_height_json(b, scale, "x_height.png", "x_height.exr");
    EXPECT_NEAR(j["mm_per_step"].get<double>() * 65535.0, double(b.max_mm - b.min_mm), 1e-6);
    EXPECT_NEAR(j["displacement_strength"].get<double>(), double(b.max_mm - b.min_mm) / 100.0, 1e-9);
    const double mid = j["displacement_midlevel"].get<double>();
    EXPECT_NEAR(b.min_mm + mid * (b.max_mm - b.min_mm), 0.0, 1e-6);  // midlevel = height 0
}

// Issue 24's check on a real tactile map: the 8-bit normal map of a GelSight capture (its
// texture isn't a perfect gradient field after quantisation), integrated at 0.085 mm per
// pixel; normals recomputed from the height agree with the map (mean cosine >= 0.995), and the
// 16-bit PNG written beside reads back in mm within one step.
TEST(HeightExport, RealCaptureNormalMapIsReproducedByItsHeight) {
    TDF_REQUIRE_SHARED_DATA("tactile/texture_samples/GreenSweater_00000.png");
    const std::string path = test::shared_data_dir() + "/tactile/texture_samples/GreenSweater_00000.png";
    const Image rgba = read_image(path);
    Image normals(rgba.width(), rgba.height(), 3);
    for (std::size_t p = 0; p < normals.pixel_count(); ++p)
        for (int c = 0; c < 3; ++c)
            normals.data()[3 * p + std::size_t(c)] = rgba.data()[p * std::size_t(rgba.channels()) + std::size_t(c)] * 2.0f - 1.0f;
    ExportScale scale;
    scale.mm_per_texel = 0.085f;
    const ExportedHeight height = export_height(normals, scale, path);
    std::printf("GreenSweater: mean cosine %.5f, height range %.4f .. %.4f mm, RMS %.4f mm\n", height.mean_cosine,
                height.min_mm, height.max_mm, rms(height.map.height));
    EXPECT_GE(height.mean_cosine, kHeightConsistencyLimit);
    EXPECT_GT(rms(height.map.height), 0.005);  // a crochet has relief of tens of micrometres at least

    const std::filesystem::path dir = std::filesystem::path(test::scratch_dir()) / "height_export";
    std::filesystem::create_directories(dir);
    write_exported_height((dir / "sweater").string(), height);
    const HeightMap exr = read_height_map((dir / "sweater_height.exr").string());
    EXPECT_FLOAT_EQ(exr.mm_per_pixel, 0.085f);
    const HeightInput png = load_height_input((dir / "sweater_height.png").string(), HeightInputOptions());
    double max_error = 0;
    for (std::size_t i = 0; i < exr.height.values().size(); ++i)
        max_error = std::max(max_error, std::abs(double(png.map.height.values()[i]) - exr.height.values()[i]));
    std::printf("16-bit PNG back in mm: max error %.3g mm (one step %.3g mm)\n", max_error, height.mm_per_step());
    EXPECT_LE(max_error, height.mm_per_step() * 0.51 + 1e-7);
}
