#pragma once
// Helpers shared by the tactile test files.
#include <tdf/core/error.h>
#include <tdf/core/image.h>
#include <tdf/core/rng.h>

#include <cmath>
#include <string>

namespace tdf::test {

/// The message of the tdf::Error that `f` throws, or "" when it throws none.
template <typename F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

/// Pearson correlation of all values of two equally sized images.
inline double correlation(const Image& a, const Image& b) {
    double ma = 0, mb = 0;
    const std::size_t n = a.values().size();
    for (std::size_t i = 0; i < n; ++i) ma += a.values()[i], mb += b.values()[i];
    ma /= double(n), mb /= double(n);
    double ab = 0, aa = 0, bb = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const double x = a.values()[i] - ma, y = b.values()[i] - mb;
        ab += x * y, aa += x * x, bb += y * y;
    }
    return ab / std::sqrt(aa * bb);
}

/// A stochastic texture with structure at several scales (sums of random oriented waves).
inline Image synthetic_texture(int size, std::uint64_t seed, int channels = 1) {
    Rng rng(seed);
    Image image(size, size, channels);
    for (int wave = 0; wave < 12; ++wave) {
        const float angle = rng.uniform(0.0f, 6.2831853f), frequency = rng.uniform(0.05f, 0.4f);
        const float phase = rng.uniform(0.0f, 6.2831853f), amplitude = rng.uniform(0.2f, 1.0f);
        const float fx = frequency * std::cos(angle), fy = frequency * std::sin(angle);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                for (int c = 0; c < channels; ++c)
                    image.at(x, y, c) +=
                        amplitude * std::sin(fx * float(x) + fy * float(y) + phase + float(c));
    }
    return image;
}

}  // namespace tdf::test
