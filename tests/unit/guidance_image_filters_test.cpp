// The guidance filters against plain, obviously correct implementations: the fast blur (blocked,
// vectorised tap sums) and the blur evaluated only where a bilinear resize reads it must give the
// numbers of the straightforward separable convolution and of blur-then-resize.
#include "common/test_images.h"
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/guidance/image_filters.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace tdf {
namespace {
using test::inner_product;
using test::random_image;

/// Coverage with a hard background block (wider than any kernel here), an antialiased edge and
/// partial values, so both the weighting and the "no weight: keep the input" rule are exercised.
Image test_mask(int w, int h) {
    Image mask(w, h, 1, 1.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (x < w / 2 && y < h / 2) mask.at(x, y, 0) = 0.0f;
            if (x == w / 2) mask.at(x, y, 0) = 0.5f;
            if ((x + 2 * y) % 7 == 0) mask.at(x, y, 0) *= 0.25f;
        }
    return mask;
}

/// The definition: out = G*(m x) / G*(m), horizontal then vertical taps with clamped borders,
/// each sum accumulated from 0 in kernel order; pixels without weight keep their value.
Image reference_blur(const Image& image, const Image& mask, float sigma) {
    const int w = image.width(), h = image.height(), c = image.channels();
    const int radius = int(std::ceil(3.0f * sigma));
    std::vector<float> kernel;
    for (int i = -radius; i <= radius; ++i)
        kernel.push_back(std::exp(-0.5f * float(i * i) / (sigma * sigma)));
    Image weighted(w, h, c + 1), horizontal(w, h, c + 1), vertical(w, h, c + 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float m = mask.empty() ? 1.0f : mask.at(x, y, 0);
            for (int ch = 0; ch < c; ++ch) weighted.at(x, y, ch) = m * image.at(x, y, ch);
            weighted.at(x, y, c) = m;
        }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = -radius; k <= radius; ++k)
                for (int ch = 0; ch <= c; ++ch)
                    horizontal.at(x, y, ch) +=
                        kernel[std::size_t(k + radius)] * weighted.at(std::clamp(x + k, 0, w - 1), y, ch);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = -radius; k <= radius; ++k)
                for (int ch = 0; ch <= c; ++ch)
                    vertical.at(x, y, ch) +=
                        kernel[std::size_t(k + radius)] * horizontal.at(x, std::clamp(y + k, 0, h - 1), ch);
    Image out = image;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (vertical.at(x, y, c) > 0.0f)
                for (int ch = 0; ch < c; ++ch)
                    out.at(x, y, ch) = vertical.at(x, y, ch) / vertical.at(x, y, c);
    return out;
}

struct Difference {
    double max_error = 0.0;
    double psnr = 0.0;  ///< dB over a peak-to-peak range of 2 (values in [-1, 1])
};

Difference compare(const Image& a, const Image& b) {
    EXPECT_EQ(a.width(), b.width());
    EXPECT_EQ(a.height(), b.height());
    EXPECT_EQ(a.channels(), b.channels());
    Difference d;
    double squared = 0.0;
    for (std::size_t i = 0; i < a.values().size(); ++i) {
        const double e = std::abs(double(a.values()[i]) - double(b.values()[i]));
        d.max_error = std::max(d.max_error, e);
        squared += e * e;
    }
    const double mse = squared / double(a.values().size());
    d.psnr = mse > 0.0 ? 10.0 * std::log10(4.0 / mse) : std::numeric_limits<double>::infinity();
    return d;
}

}  // namespace

TEST(GuidanceImageFilters, GaussianBlurEqualsThePlainSeparableConvolution) {
    // Odd sizes: rows are not multiples of the 32-float blocks, so the tails are exercised too.
    for (const int channels : {1, 3}) {
        for (const float sigma : {1.0f, 3.0f, 9.5f}) {
            const Image image = random_image(53, 37, channels, 7);
            const Image mask = test_mask(53, 37);
            const Difference masked =
                compare(gaussian_blur_masked(image, mask, sigma), reference_blur(image, mask, sigma));
            const Difference plain =
                compare(gaussian_blur_masked(image, Image(), sigma), reference_blur(image, Image(), sigma));
            std::printf(
                "blur %d channel(s), sigma %.1f: max error %.3g (PSNR %.1f dB) masked, %.3g (%.1f dB) "
                "unmasked\n",
                channels,
                double(sigma),
                masked.max_error,
                masked.psnr,
                plain.max_error,
                plain.psnr);
            EXPECT_LE(masked.max_error, 1e-6);
            EXPECT_LE(plain.max_error, 1e-6);
        }
    }
}

TEST(GuidanceImageFilters, BlurAtTheResizedPixelsEqualsBlurThenResize) {
    struct Case {
        int width, height, out_width, out_height;
        float sigma;
    };
    // The main job's coarse copy (512 -> 27, sigma 0.5 / scale), a non-square shrink, a mild
    // one, a magnification (sigma still applied) and no blur at all.
    const Case cases[] = {{512, 512, 27, 27, 9.48f},
                          {130, 90, 17, 11, 3.8f},
                          {64, 64, 48, 48, 0.67f},
                          {20, 20, 50, 50, 1.0f},
                          {40, 30, 13, 9, 0.0f}};
    for (const Case& c : cases) {
        const Image image = random_image(c.width, c.height, 3, 11);
        const Image mask = test_mask(c.width, c.height);
        for (const bool use_mask : {true, false}) {
            const Image& m = use_mask ? mask : Image();
            const Image expected =
                resize_bilinear(gaussian_blur_masked(image, m, c.sigma), c.out_width, c.out_height);
            const Difference d =
                compare(gaussian_blur_resized(image, m, c.sigma, c.out_width, c.out_height), expected);
            std::printf("%dx%d -> %dx%d, sigma %.2f, %s: max error %.3g (PSNR %.1f dB)\n",
                        c.width,
                        c.height,
                        c.out_width,
                        c.out_height,
                        double(c.sigma),
                        use_mask ? "masked" : "unmasked",
                        d.max_error,
                        d.psnr);
            EXPECT_LE(d.max_error, 1e-6);
        }
    }
    // The mask itself, as the exemplar backend resamples it (1 channel, no weights).
    const Image mask = test_mask(512, 512);
    EXPECT_LE(compare(gaussian_blur_resized(mask, Image(), 9.48f, 27, 27),
                      resize_bilinear(gaussian_blur_masked(mask, Image(), 9.48f), 27, 27))
                  .max_error,
              1e-6);
}

TEST(GuidanceImageFilters, SameBitsOnOneAndManyThreads) {
    const Image image = random_image(300, 200, 3, 3);
    const Image mask = test_mask(300, 200);
    const Image blurred = gaussian_blur_masked(image, mask, 3.0f);
    const Image resized = gaussian_blur_resized(image, mask, 6.0f, 25, 17);
    ThreadLimit one(1);
    EXPECT_EQ(gaussian_blur_masked(image, mask, 3.0f).values(), blurred.values());
    EXPECT_EQ(gaussian_blur_resized(image, mask, 6.0f, 25, 17).values(), resized.values());
}

}  // namespace tdf
