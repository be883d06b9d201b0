#include <tdf/tactile/touch_comparison.h>

#include <tdf/core/error.h>
#include <tdf/tactile/height_export.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/tactile/normal_map.h>

#include <algorithm>
#include <cmath>

namespace tdf {

Image remove_quadratic(const Image& height) {
    TDF_CHECK(height.channels() == 1);
    const int w = height.width(), h = height.height();
    // Least squares over the basis 1, x, y, x^2, xy, y^2 (coordinates in [-1, 1]): normal
    // equations, solved by Gaussian elimination with partial pivoting.
    double a[6][7] = {};
    const auto basis = [&](int x, int y, double* f) {
        const double u = 2.0 * (x + 0.5) / w - 1.0, v = 2.0 * (y + 0.5) / h - 1.0;
        f[0] = 1, f[1] = u, f[2] = v, f[3] = u * u, f[4] = u * v, f[5] = v * v;
    };
    double f[6];
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            basis(x, y, f);
            for (int i = 0; i < 6; ++i) {
                for (int j = 0; j < 6; ++j) a[i][j] += f[i] * f[j];
                a[i][6] += f[i] * height.at(x, y, 0);
            }
        }
    for (int c = 0; c < 6; ++c) {
        int pivot = c;
        for (int r = c + 1; r < 6; ++r)
            if (std::abs(a[r][c]) > std::abs(a[pivot][c])) pivot = r;
        for (int k = 0; k < 7; ++k) std::swap(a[c][k], a[pivot][k]);
        TDF_CHECK(std::abs(a[c][c]) > 0);
        for (int r = 0; r < 6; ++r) {
            if (r == c) continue;
            const double factor = a[r][c] / a[c][c];
            for (int k = c; k < 7; ++k) a[r][k] -= factor * a[c][k];
        }
    }
    Image out(w, h, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            basis(x, y, f);
            double fit = 0;
            for (int i = 0; i < 6; ++i) fit += f[i] * a[i][6] / a[i][i];
            out.at(x, y, 0) = float(height.at(x, y, 0) - fit);
        }
    return out;
}

ReliefMeasure measure_relief(const Image& raw_height_mm, float mm_per_pixel, const Image& mask) {
    TDF_CHECK(raw_height_mm.channels() == 1 && mm_per_pixel > 0);
    TDF_CHECK(mask.empty() || mask.pixel_count() == raw_height_mm.pixel_count());
    const Image height_mm = remove_quadratic(raw_height_mm);
    const MaterialStatistics stats =
        material_statistics(detail_slopes(normals_from_height(height_mm, 1.0f / mm_per_pixel)), mask, 90.0);
    const Image low = gaussian_blur_mirrored(height_mm, kDetailSigmaPx);
    double sum = 0, count = 0;
    for (std::size_t p = 0; p < height_mm.pixel_count(); ++p) {
        if (!mask.empty() && !(mask.data()[p] > 0)) continue;
        const double d = double(height_mm.data()[p]) - low.data()[p];
        sum += d * d;
        count += 1;
    }
    ReliefMeasure m;
    m.detail_tilt = stats.mean_tilt;
    m.height_rms_mm = count > 0 ? std::sqrt(sum / count) : 0.0;
    m.scale_energy = stats.scale_energy;
    return m;
}

ReliefMeasure measure_capture(const Image& normals, float mm_per_pixel, int window, CaptureArea area) {
    Image height = integrate_normal_map(normals, false, "capture");
    for (float& v : height.values()) v *= mm_per_pixel;
    const Image region = area == CaptureArea::Contact ? texture_region(detail_slopes(normals).tilt) : Image();
    const int w = height.width(), h = height.height();
    if (window <= 0 || window >= std::min(w, h)) return measure_relief(height, mm_per_pixel, region);
    // Pad-sized windows on a grid over the capture: the high-pass and the form removal then see
    // what they see on a touch of that size.
    std::vector<ReliefMeasure> windows;
    for (int y0 = 0; y0 + window <= h; y0 += window)
        for (int x0 = 0; x0 + window <= w; x0 += window) {
            Image crop(window, window, 1), crop_region;
            for (int y = 0; y < window; ++y)
                for (int x = 0; x < window; ++x) crop.at(x, y, 0) = height.at(x0 + x, y0 + y, 0);
            if (!region.empty()) {
                crop_region = Image(window, window, 1);
                double inside = 0;
                for (int y = 0; y < window; ++y)
                    for (int x = 0; x < window; ++x) {
                        crop_region.at(x, y, 0) = region.at(x0 + x, y0 + y, 0);
                        inside += crop_region.at(x, y, 0) > 0 ? 1.0 : 0.0;
                    }
                if (inside < 0.5 * double(window) * double(window)) continue;
            }
            windows.push_back(measure_relief(crop, mm_per_pixel, crop_region));
        }
    if (windows.empty()) return measure_relief(height, mm_per_pixel, region);
    return compare_touches(windows.front(), windows).touches;  // the windows' mean
}

TouchRoundTrip compare_touches(const ReliefMeasure& capture, const std::vector<ReliefMeasure>& touches) {
    TDF_CHECK(!touches.empty());
    TouchRoundTrip r;
    r.capture = capture;
    r.touches.scale_energy.assign(capture.scale_energy.size(), 0.0);
    for (const ReliefMeasure& t : touches) {
        r.touches.detail_tilt += t.detail_tilt / double(touches.size());
        r.touches.height_rms_mm += t.height_rms_mm / double(touches.size());
        TDF_CHECK_EQ(t.scale_energy.size(), capture.scale_energy.size());
        for (std::size_t b = 0; b < t.scale_energy.size(); ++b)
            r.touches.scale_energy[b] += t.scale_energy[b] / double(touches.size());
    }
    r.tilt_ratio = capture.detail_tilt > 0 ? r.touches.detail_tilt / capture.detail_tilt : 0.0;
    r.height_rms_ratio = capture.height_rms_mm > 0 ? r.touches.height_rms_mm / capture.height_rms_mm : 0.0;
    for (std::size_t b = 0; b < capture.scale_energy.size(); ++b)
        r.spectrum_distance += 0.5 * std::abs(r.touches.scale_energy[b] - capture.scale_energy[b]);
    return r;
}

Json TouchRoundTrip::to_json() const {
    const auto measure = [](const ReliefMeasure& m) {
        return Json{{"detail_tilt_degrees", m.detail_tilt}, {"height_rms_mm", m.height_rms_mm},
                    {"scale_energy", m.scale_energy}};
    };
    return Json{{"tilt_ratio", tilt_ratio},
                {"spectrum_distance", spectrum_distance},
                {"height_rms_ratio", height_rms_ratio},
                {"capture", measure(capture)},
                {"touches", measure(touches)}};
}

}  // namespace tdf
