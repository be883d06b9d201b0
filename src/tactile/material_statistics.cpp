#include <tdf/tactile/material_statistics.h>

#include <tdf/core/error.h>
#include <tdf/core/image_ops.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kTiltBins = 16;
constexpr int kOrientationBins = 8;
constexpr float kScaleSigmas[] = {1.0f, 2.0f, 4.0f, 8.0f};

// Mean over a (2r+1)^2 window with edge-replicated borders (separable).
Image box_mean_replicated(const Image& in, int r) {
    const int w = in.width(), h = in.height();
    Image rows(w, h, 1), out(w, h, 1);
    const double k = 1.0 / double(2 * r + 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double s = 0;
            for (int d = -r; d <= r; ++d) s += in.at(std::clamp(x + d, 0, w - 1), y, 0);
            rows.at(x, y, 0) = float(s * k);
        }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double s = 0;
            for (int d = -r; d <= r; ++d) s += rows.at(x, std::clamp(y + d, 0, h - 1), 0);
            out.at(x, y, 0) = float(s * k);
        }
    return out;
}

// numpy.percentile with linear interpolation.
double percentile(std::vector<float> values, double q) {
    TDF_CHECK(!values.empty());
    std::sort(values.begin(), values.end());
    const double position = q / 100.0 * double(values.size() - 1);
    const std::size_t lo = std::size_t(std::floor(position));
    const std::size_t hi = std::min(lo + 1, values.size() - 1);
    const double t = position - double(lo);
    return double(values[lo]) + t * (double(values[hi]) - double(values[lo]));
}

double l1(const std::vector<double>& a, const std::vector<double>& b) {
    TDF_CHECK_EQ(a.size(), b.size());
    double d = 0;
    for (std::size_t i = 0; i < a.size(); ++i) d += std::abs(a[i] - b[i]);
    return d;
}

void normalise(std::vector<double>& h) {
    double total = 0;
    for (double v : h) total += v;
    if (total > 0)
        for (double& v : h) v /= total;
}

}  // namespace

Image gaussian_blur_mirrored(const Image& image, float sigma_px) {
    TDF_CHECK(sigma_px > 0.0f);
    // In double, as the yardstick (numpy) sums.
    const std::vector<double> kernel = gaussian_kernel<double>(sigma_px, int(3.0f * sigma_px + 1.0f));
    Image out(image.width(), image.height(), image.channels());
    convolve_separable(image, out, kernel, Addressing::Mirror);
    return out;
}

DetailSlopes detail_slopes(const Image& normals, float sigma_px) {
    TDF_CHECK(normals.channels() >= 3);
    const int w = normals.width(), h = normals.height();
    DetailSlopes d;
    d.slopes = Image(w, h, 2);
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        const float* n = normals.data() + p * std::size_t(normals.channels());
        // Matches the yardstick: n normalised, then nz clamped to 1e-3.
        const double length = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]) + 1e-12;
        const double nz = std::max(double(n[2]) / length, 1e-3);
        d.slopes.data()[2 * p] = float(n[0] / length / nz);
        d.slopes.data()[2 * p + 1] = float(n[1] / length / nz);
    }
    const Image low = gaussian_blur_mirrored(d.slopes, sigma_px);
    d.tilt = Image(w, h, 1);
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        float& sx = d.slopes.data()[2 * p];
        float& sy = d.slopes.data()[2 * p + 1];
        sx -= low.data()[2 * p];
        sy -= low.data()[2 * p + 1];
        d.tilt.data()[p] = float(std::atan(std::hypot(double(sx), double(sy))) * 180.0 / kPi);
    }
    return d;
}

Image texture_region(const Image& tilt_degrees) {
    TDF_CHECK_EQ(tilt_degrees.channels(), 1);
    const Image local = box_mean_replicated(tilt_degrees, 7);
    const double threshold = 0.5 * percentile({local.values().begin(), local.values().end()}, 90.0);
    Image mask(tilt_degrees.width(), tilt_degrees.height(), 1);
    for (std::size_t p = 0; p < mask.pixel_count(); ++p)
        mask.data()[p] = double(local.data()[p]) >= threshold ? 1.0f : 0.0f;
    return mask;
}

double mask_fraction(const Image& mask) {
    if (mask.empty()) return 1.0;
    std::size_t count = 0;
    for (float v : mask.values()) count += v != 0.0f;
    return double(count) / double(mask.pixel_count());
}

MaterialStatistics material_statistics(const DetailSlopes& detail, const Image& mask, double tilt_range) {
    TDF_CHECK(tilt_range > 0.0);
    const Image& tilt = detail.tilt;
    if (!mask.empty()) {
        TDF_CHECK_EQ(mask.width(), tilt.width());
        TDF_CHECK_EQ(mask.height(), tilt.height());
    }
    auto counted = [&](std::size_t p) { return mask.empty() || mask.data()[p] != 0.0f; };
    MaterialStatistics s;
    s.fraction = mask_fraction(mask);
    s.tilt_histogram.assign(kTiltBins, 0.0);
    s.orientation_histogram.assign(kOrientationBins, 0.0);
    double sum = 0, flat = 0, count = 0;
    for (std::size_t p = 0; p < tilt.pixel_count(); ++p) {
        if (!counted(p)) continue;
        const double t = tilt.data()[p];
        sum += t;
        flat += t < kFlatDegrees;
        count += 1;
        s.tilt_histogram[std::size_t(std::min(kTiltBins - 1, int(t / tilt_range * kTiltBins)))] += 1;
        const double sx = detail.slopes.data()[2 * p], sy = detail.slopes.data()[2 * p + 1];
        double angle = std::atan2(sy, sx);  // direction modulo 180 degrees, in [0, pi)
        if (angle < 0) angle += kPi;
        if (angle >= kPi) angle -= kPi;
        const int bin = std::min(kOrientationBins - 1, int(angle / kPi * kOrientationBins));
        s.orientation_histogram[std::size_t(bin)] += std::hypot(sx, sy);
    }
    if (count > 0) s.mean_tilt = sum / count, s.flat_fraction = flat / count;
    normalise(s.tilt_histogram);
    normalise(s.orientation_histogram);

    // Octave bands of the slope field: s - G1 s, G1 s - G2 s, G2 s - G4 s, G4 s - G8 s, G8 s.
    std::vector<Image> levels{detail.slopes};
    for (float sigma : kScaleSigmas) levels.push_back(gaussian_blur_mirrored(detail.slopes, sigma));
    s.scale_energy.assign(levels.size(), 0.0);
    for (std::size_t band = 0; band < levels.size(); ++band) {
        const Image& a = levels[band];
        const Image* b = band + 1 < levels.size() ? &levels[band + 1] : nullptr;
        double energy = 0;
        for (std::size_t p = 0; p < tilt.pixel_count(); ++p) {
            if (!counted(p)) continue;
            for (std::size_t c = 0; c < 2; ++c) {
                const double v = double(a.data()[2 * p + c]) - (b ? double(b->data()[2 * p + c]) : 0.0);
                energy += v * v;
            }
        }
        s.scale_energy[band] = energy;
    }
    normalise(s.scale_energy);
    return s;
}

double texture_distance(const MaterialStatistics& a, const MaterialStatistics& b) {
    return (l1(a.tilt_histogram, b.tilt_histogram) + l1(a.orientation_histogram, b.orientation_histogram) +
            l1(a.scale_energy, b.scale_energy)) /
           6.0;
}

namespace {
double rounded(double value, int decimals) {
    const double scale = std::pow(10.0, decimals);
    return std::round(value * scale) / scale;
}
}  // namespace

double rounded_significant(double value, int digits) {
    if (value == 0 || !std::isfinite(value)) return value;
    return rounded(value, digits - 1 - int(std::floor(std::log10(std::fabs(value)))));
}

Json MaterialComparison::to_json() const {
    return {{"region_fraction", rounded(region.fraction, 4)},
            {"region_mean_tilt", rounded(region.mean_tilt, 4)},
            {"region_flat", rounded(region.flat_fraction, 4)},
            {"out_mean_tilt", rounded(output.mean_tilt, 4)},
            {"out_flat", rounded(output.flat_fraction, 4)},
            {"tilt_ratio", rounded(tilt_ratio, 4)},
            {"distance", rounded(distance, 4)},
            {"tilt_l1", rounded(tilt_l1, 3)},
            {"orientation_l1", rounded(orientation_l1, 3)},
            {"scale_l1", rounded(scale_l1, 3)},
            {"input_mean_tilt", rounded(input_mean_tilt, 4)},
            {"input_flat", rounded(input_flat, 4)},
            {"input_tilt_ratio", rounded(input_tilt_ratio, 4)}};
}

std::string MaterialComparison::json() const { return to_json().dump(); }

MaterialComparison compare_material(const Image& input, const Image& region, const Image& output) {
    const DetailSlopes in = detail_slopes(input), out = detail_slopes(output);
    const Image mask = region.empty() ? texture_region(in.tilt) : region;
    MaterialComparison c;
    // The histogram range follows the region's relief, so that bins resolve it whatever its
    // amplitude; a first pass gives the region's mean tilt.
    const double mean = material_statistics(in, mask, 90.0).mean_tilt;
    const double range = std::max(3.0 * mean, 1e-3);
    c.region = material_statistics(in, mask, range);
    c.output = material_statistics(out, Image(), range);
    c.tilt_ratio = c.output.mean_tilt / std::max(c.region.mean_tilt, 1e-9);
    c.flat_excess = c.output.flat_fraction - c.region.flat_fraction;
    c.distance = texture_distance(c.region, c.output);
    c.tilt_l1 = l1(c.region.tilt_histogram, c.output.tilt_histogram);
    c.orientation_l1 = l1(c.region.orientation_histogram, c.output.orientation_histogram);
    c.scale_l1 = l1(c.region.scale_energy, c.output.scale_energy);
    const MaterialStatistics whole = material_statistics(in, Image(), range);
    c.input_mean_tilt = whole.mean_tilt;
    c.input_flat = whole.flat_fraction;
    c.input_tilt_ratio = whole.mean_tilt / std::max(c.region.mean_tilt, 1e-9);
    return c;
}

std::vector<std::string> check_material(const MaterialComparison& c, const MaterialLimits& limits) {
    std::vector<std::string> bad;
    if (c.tilt_ratio < limits.min_ratio)
        bad.push_back(fmt::format("flatter than the input: detail tilt {:.2f} of the input region's (at least {:.2f})",
                                  c.tilt_ratio,
                                  limits.min_ratio));
    if (c.tilt_ratio > limits.max_ratio)
        bad.push_back(fmt::format("steeper than the input: detail tilt {:.2f} of the input region's (at most {:.2f})",
                                  c.tilt_ratio,
                                  limits.max_ratio));
    if (c.flat_excess > limits.flat_slack)
        bad.push_back(fmt::format("{:.1f} % flat texels against {:.1f} % in the input region",
                                  100.0 * c.output.flat_fraction,
                                  100.0 * c.region.flat_fraction));
    if (c.distance > limits.max_distance)
        bad.push_back(fmt::format("texture distance {:.3f} to the input region (at most {:.3f})", c.distance, limits.max_distance));
    return bad;
}

double material_misses(const std::vector<MaterialComparison>& comparisons, const MaterialLimits& limits) {
    double miss = 0;
    for (const MaterialComparison& c : comparisons) {
        miss += std::max({0.0, limits.min_ratio - c.tilt_ratio, c.tilt_ratio - limits.max_ratio});
        miss += std::max(0.0, c.flat_excess - limits.flat_slack);
        miss += std::max(0.0, c.distance - limits.max_distance);
    }
    return miss;
}

SeamStatistics seam_statistics(const Image& height, const Image& seams) {
    TDF_CHECK(height.channels() >= 1);
    const int w = height.width(), h = height.height();
    SeamStatistics s;
    if (w < 3 || h < 3) return s;
    if (!seams.empty()) {
        TDF_CHECK(seams.width() == w && seams.height() == h);
        double on = 0, off = 0, n_on = 0, n_off = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const double gx = height.at((x + 1) % w, y, 0) - height.at(x, y, 0);
                const double gy = height.at(x, (y + 1) % h, 0) - height.at(x, y, 0);
                const double e = gx * gx + gy * gy;
                if (seams.at(x, y, 0) != 0.0f)
                    on += e, n_on += 1;
                else
                    off += e, n_off += 1;
            }
        if (n_on > 0 && n_off > 0 && off > 0) s.cut_ratio = (on / n_on) / (off / n_off);
    }
    // Mean |step| from line i to line i + 1 (wrapping), columns or rows.
    // (Summed over the channels: a normal map's two slopes.)
    const int channels = height.channels();
    auto step = [&](bool columns, int i) {
        const int along = columns ? h : w, across = columns ? w : h;
        double sum = 0;
        for (int k = 0; k < along; ++k)
            for (int c = 0; c < channels; ++c)
                sum += columns ? std::abs(height.at((i + 1) % across, k, c) - height.at(i, k, c))
                               : std::abs(height.at(k, (i + 1) % across, c) - height.at(k, i, c));
        return sum / along;
    };
    auto same = [&](bool columns, int a, int b) {
        const int along = columns ? h : w;
        for (int k = 0; k < along; ++k)
            for (int c = 0; c < channels; ++c)
                if ((columns ? height.at(a, k, c) : height.at(k, a, c)) != (columns ? height.at(b, k, c) : height.at(k, b, c)))
                    return false;
        return true;
    };
    for (bool columns : {true, false}) {
        const int across = columns ? w : h;
        // The wrap's step against the steps of the lines next to it, which cross the same
        // content: one line's step varies with what it crosses (a band of pebble edges), so
        // against the mean of all lines a seamless torus fails wherever its wrap falls in a
        // rough band (Football rows: 27 % of ordinary rows step more than 1.2x the mean).
        const int wrap = across - 1;
        const int k = std::min(kWrapBaselineLines, (across - 1) / 2);
        double nearby = 0;
        for (int d = 1; d <= k; ++d) nearby += step(columns, wrap - d) + step(columns, (wrap + d) % across);
        nearby /= 2.0 * k;
        (columns ? s.wrap_ratio_columns : s.wrap_ratio_rows) = nearby > 0 ? step(columns, wrap) / nearby : 0.0;
        s.duplicated_border = s.duplicated_border || same(columns, 0, 1) || same(columns, across - 1, across - 2);
    }
    return s;
}

std::string SeamStatistics::json() const {
    return fmt::format("{{\"cut_gradient_ratio\": {:.3f}, \"wrap_step_ratio_columns\": {:.3f}, "
                       "\"wrap_step_ratio_rows\": {:.3f}, \"duplicated_border\": {}}}",
                       cut_ratio,
                       wrap_ratio_columns,
                       wrap_ratio_rows,
                       duplicated_border);
}

Image quantized_normals(const Image& normals, int bits) {
    TDF_CHECK(bits == 8 || bits == 16);
    const float max_value = bits == 16 ? 65535.0f : 255.0f;
    Image out = normals;
    for (float& v : out.values()) {
        // As write_png(Quantize::Truncate) then read_image: clamp, floor, divide, decode.
        const float e = std::clamp(v * 0.5f + 0.5f, 0.0f, 1.0f) * max_value;
        v = std::floor(e) / max_value * 2.0f - 1.0f;
    }
    return out;
}

SeamStatistics normal_map_wrap_statistics(const Image& normals) {
    TDF_CHECK(normals.channels() >= 3);
    Image slopes(normals.width(), normals.height(), 2);
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        const float* n = normals.data() + std::size_t(normals.channels()) * p;
        const float z = std::max(n[2], 1e-3f);
        slopes.data()[2 * p] = n[0] / z;
        slopes.data()[2 * p + 1] = n[1] / z;
    }
    return seam_statistics(slopes, Image());
}

}  // namespace tdf
