#include <tdf/tactile/resample.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace tdf {

namespace {

constexpr int kLobes = 4;

double lanczos(double x) {
    if (std::fabs(x) < 1e-12) return 1.0;
    if (std::fabs(x) >= kLobes) return 0.0;
    const double pi = 3.14159265358979323846;
    return kLobes * std::sin(pi * x) * std::sin(pi * x / kLobes) / (pi * pi * x * x);
}

// Sparse 1-D resampling matrix from `in` samples to `out` samples.
struct Taps {
    std::vector<int> index;     // clamped source indices, out * taps
    std::vector<float> weight;  // normalised weights, out * taps
    int taps = 0;
};

Taps make_taps(int in, int out) {
    const double scale = double(in) / double(out);
    const double stretch = std::max(1.0, scale);  // widen the kernel when shrinking
    Taps t;
    t.taps = 2 * int(std::ceil(kLobes * stretch));
    t.index.resize(std::size_t(out) * std::size_t(t.taps));
    t.weight.resize(t.index.size());
    for (int o = 0; o < out; ++o) {
        const double centre = (o + 0.5) * scale - 0.5;
        const int start = int(std::floor(centre)) - t.taps / 2 + 1;
        double total = 0;
        for (int k = 0; k < t.taps; ++k) {
            const double w = lanczos((start + k - centre) / stretch);
            t.index[std::size_t(o) * std::size_t(t.taps) + std::size_t(k)] = std::clamp(start + k, 0, in - 1);
            t.weight[std::size_t(o) * std::size_t(t.taps) + std::size_t(k)] = float(w);
            total += w;
        }
        for (int k = 0; k < t.taps; ++k)
            t.weight[std::size_t(o) * std::size_t(t.taps) + std::size_t(k)] /= float(total);
    }
    return t;
}

}  // namespace

Image crop(const Image& image, int x, int y, int width, int height) {
    TDF_CHECK(x >= 0 && y >= 0 && width >= 0 && height >= 0);
    TDF_CHECK(x + width <= image.width() && y + height <= image.height());
    const int c = image.channels();
    Image out(width, height, c);
    for (int row = 0; row < height; ++row)
        std::copy(image.pixel(x, y + row),
                  image.pixel(x, y + row) + std::size_t(width) * std::size_t(c),
                  out.pixel(0, row));
    return out;
}

namespace {

// Resamples along x (`horizontal`) or y with precomputed taps; the other axis is unchanged.
Image resample_axis(const Image& image, const Taps& taps, int out_size, bool horizontal) {
    const int c = image.channels();
    const int width = horizontal ? out_size : image.width(), height = horizontal ? image.height() : out_size;
    Image out(width, height, c);
    parallel_for(std::size_t(height), 16, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < width; ++x) {
                const std::size_t first = std::size_t(horizontal ? x : y) * std::size_t(taps.taps);
                for (int k = 0; k < c; ++k) {
                    float sum = 0;
                    for (int t = 0; t < taps.taps; ++t) {
                        const int source = taps.index[first + std::size_t(t)];
                        sum += taps.weight[first + std::size_t(t)] *
                               (horizontal ? image.at(source, y, k) : image.at(x, source, k));
                    }
                    out.at(x, y, k) = sum;
                }
            }
    });
    return out;
}

}  // namespace

Image resize_lanczos(const Image& image, int width, int height) {
    TDF_CHECK(width > 0 && height > 0 && !image.empty());
    if (width == image.width() && height == image.height()) return image;
    const Image horizontal = resample_axis(image, make_taps(image.width(), width), width, true);
    return resample_axis(horizontal, make_taps(image.height(), height), height, false);
}

}  // namespace tdf
