#include "common/test_images.h"
#include <tdf/core/error.h>
#include <tdf/core/image_ops.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

using namespace tdf;

namespace {
using test::inner_product;
using test::random_image;

double mean(const Image& image) {
    double s = 0;
    for (float v : image.values()) s += v;
    return s / double(image.values().size());
}

// value = 10 x + y + 100 c at pixel centre indices, so every pixel and channel differs.
Image coordinate_image(int w, int h, int c) {
    Image img(w, h, c);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < c; ++k) img.at(x, y, k) = float(10 * x + y + 100 * k);
    return img;
}

float sample1(const Image& image, float x, float y, Addressing mode) {
    float out[1];
    sample_bilinear_texel(image, x, y, mode, out);
    return out[0];
}

}  // namespace

TEST(ImageOps, AddressingModes) {
    const std::vector<int> indices{-5, -4, -3, -2, -1, 0, 1, 2, 3, 4, 5, 6, 7, 8};
    const std::vector<int> clamp{0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3};
    const std::vector<int> wrap{3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0};
    const std::vector<int> mirror{1, 2, 3, 2, 1, 0, 1, 2, 3, 2, 1, 0, 1, 2};  // reflect-101, period 6
    const std::vector<int> border{-1, -1, -1, -1, -1, 0, 1, 2, 3, -1, -1, -1, -1, -1};
    for (std::size_t i = 0; i < indices.size(); ++i) {
        EXPECT_EQ(address(indices[i], 4, Addressing::Clamp), clamp[i]) << indices[i];
        EXPECT_EQ(address(indices[i], 4, Addressing::Wrap), wrap[i]) << indices[i];
        EXPECT_EQ(address(indices[i], 4, Addressing::Mirror), mirror[i]) << indices[i];
        EXPECT_EQ(address(indices[i], 4, Addressing::Border), border[i]) << indices[i];
    }
    for (int i = -3; i <= 3; ++i) {  // a single pixel: everything but Border reads it
        EXPECT_EQ(address(i, 1, Addressing::Clamp), 0);
        EXPECT_EQ(address(i, 1, Addressing::Wrap), 0);
        EXPECT_EQ(address(i, 1, Addressing::Mirror), 0);
        EXPECT_EQ(address(i, 1, Addressing::Border), i == 0 ? 0 : -1);
    }
}

TEST(ImageOps, BilinearSamplingAtCentresIsExactInEveryMode) {
    const Image image = coordinate_image(5, 3, 2);
    for (Addressing mode : {Addressing::Clamp, Addressing::Wrap, Addressing::Border})
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 5; ++x) {
                float out[2];
                sample_bilinear_texel(image, float(x), float(y), mode, out);
                EXPECT_EQ(out[0], image.at(x, y, 0));
                EXPECT_EQ(out[1], image.at(x, y, 1));
                // The UV of the same centre.
                sample_bilinear_uv(image, (float(x) + 0.5f) / 5.f, 1.f - (float(y) + 0.5f) / 3.f, mode, out);
                EXPECT_NEAR(out[0], image.at(x, y, 0), 1e-4f);
            }
}

TEST(ImageOps, BilinearSamplingInsideInterpolates) {
    const Image image = coordinate_image(5, 3, 1);
    for (Addressing mode : {Addressing::Clamp, Addressing::Wrap, Addressing::Border}) {
        EXPECT_FLOAT_EQ(sample1(image, 1.25f, 0.5f, mode), 10 * 1.25f + 0.5f);
        EXPECT_FLOAT_EQ(sample1(image, 3.5f, 1.75f, mode), 10 * 3.5f + 1.75f);
    }
}

TEST(ImageOps, BilinearSamplingOutsideFollowsTheAddressing) {
    const Image image = coordinate_image(5, 3, 1);  // columns 0, 10, .., 40; rows +0, +1, +2
    // Clamp: the edge pixel, exactly.
    EXPECT_EQ(sample1(image, -0.5f, 1.0f, Addressing::Clamp), 1.0f);
    EXPECT_EQ(sample1(image, 7.0f, 5.0f, Addressing::Clamp), 42.0f);
    EXPECT_EQ(sample1(image, std::numeric_limits<float>::quiet_NaN(), 2.0f, Addressing::Clamp), 2.0f);
    // Wrap: half way between the last and the first column; a whole period away is the same.
    EXPECT_FLOAT_EQ(sample1(image, -0.5f, 1.0f, Addressing::Wrap), 0.5f * (40 + 0) + 1.0f);
    EXPECT_FLOAT_EQ(sample1(image, 4.5f, 1.0f, Addressing::Wrap), 0.5f * (40 + 0) + 1.0f);
    EXPECT_FLOAT_EQ(sample1(image, 1.25f + 5.f, 0.5f - 3.f, Addressing::Wrap), 10 * 1.25f + 0.5f);
    // Border: zero outside, so half the edge value half a pixel out, and nothing far away.
    EXPECT_FLOAT_EQ(sample1(image, 4.5f, 1.0f, Addressing::Border), 0.5f * 41.0f);
    EXPECT_FLOAT_EQ(sample1(image, 2.0f, -0.25f, Addressing::Border), 0.75f * 20.0f);
    EXPECT_EQ(sample1(image, -3.0f, 1.0f, Addressing::Border), 0.0f);
    EXPECT_EQ(sample1(image, 1e20f, 1.0f, Addressing::Border), 0.0f);
    EXPECT_EQ(sample1(image, std::numeric_limits<float>::infinity(), 1.0f, Addressing::Border), 0.0f);
}

TEST(ImageOps, UvToTexelPutsCentresAtIntegers) {
    const TexelPoint t = uv_to_texel(0.5f / 8.f, 1.f - 2.5f / 4.f, 8, 4);
    EXPECT_FLOAT_EQ(t.x, 0.0f);
    EXPECT_FLOAT_EQ(t.y, 2.0f);  // v up: row 0 is the top
}

TEST(ImageOps, ResizeKeepsConstantsForAnySize) {
    const Image flat(7, 5, 3, 0.3f);
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{3, 2}, {11, 13}, {1, 1}, {7, 9}, {2, 5}}) {
        for (const Image& out : {resize_bilinear(flat, w, h), resize_area(flat, w, h), resize_lanczos(flat, w, h)}) {
            ASSERT_EQ(out.width(), w);
            ASSERT_EQ(out.height(), h);
            for (float v : out.values()) EXPECT_NEAR(v, 0.3f, 1e-6f) << w << "x" << h;
        }
    }
}

TEST(ImageOps, BilinearResizeReproducesALinearRamp) {
    // f = 2 x - 3 y + 1 at source centres; output pixel o samples the source at
    // (o + 0.5) src / dst - 0.5, clamped to the edge centres.
    const int sw = 9, sh = 7;
    Image ramp(sw, sh, 1);
    for (int y = 0; y < sh; ++y)
        for (int x = 0; x < sw; ++x) ramp.at(x, y, 0) = 2.f * float(x) - 3.f * float(y) + 1.f;
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{4, 3}, {5, 5}, {17, 13}, {9, 2}}) {
        const Image out = resize_bilinear(ramp, w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const double sx = std::clamp((x + 0.5) * sw / w - 0.5, 0.0, double(sw - 1));
                const double sy = std::clamp((y + 0.5) * sh / h - 0.5, 0.0, double(sh - 1));
                EXPECT_NEAR(out.at(x, y, 0), 2 * sx - 3 * sy + 1, 1e-4) << w << "x" << h << " at " << x << "," << y;
            }
    }
}

TEST(ImageOps, AreaResizeAveragesAndConservesTheMean) {
    // Integer ratio: the mean of each block, which for a ramp is its value at the block centre.
    Image ramp(12, 6, 1);
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 12; ++x) ramp.at(x, y, 0) = float(x) + 0.5f * float(y);
    const Image down = resize_area(ramp, 4, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) EXPECT_FLOAT_EQ(down.at(x, y, 0), float(3 * x + 1) + 0.5f * float(3 * y + 1));
    // Odd sizes: partial pixels weighted by coverage, so the mean is kept.
    const Image noise = random_image(13, 7, 2, 4);
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{6, 3}, {5, 2}, {1, 1}, {4, 7}})
        EXPECT_NEAR(mean(resize_area(noise, w, h)), mean(noise), 1e-6) << w << "x" << h;
}

TEST(ImageOps, BoxDownsampleHalvesWithAreaWeights) {
    const Image image = coordinate_image(5, 4, 1);
    const Image down = downsample_box(image);
    ASSERT_EQ(down.width(), 2);
    ASSERT_EQ(down.height(), 2);
    // Columns: output 0 covers [0, 2.5) -> weights 0.4, 0.4, 0.2 on columns 0, 1, 2.
    const float col0 = 0.4f * 0 + 0.4f * 10 + 0.2f * 20, col1 = 0.2f * 20 + 0.4f * 30 + 0.4f * 40;
    EXPECT_NEAR(down.at(0, 0, 0), col0 + 0.5f, 1e-5f);  // rows 0, 1
    EXPECT_NEAR(down.at(1, 1, 0), col1 + 2.5f, 1e-5f);  // rows 2, 3
    // A single row or column stays one pixel wide.
    EXPECT_EQ(downsample_box(Image(1, 6, 2)).width(), 1);
    EXPECT_EQ(downsample_box(Image(1, 6, 2)).height(), 3);
}

TEST(ImageOps, BoxDownsampleAdjointIsTheTranspose) {
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{8, 6}, {7, 5}, {9, 4}, {1, 5}, {3, 1}, {2, 2}}) {
        const Image x = random_image(w, h, 3, std::uint64_t(w * 31 + h));
        const Image coarse_x = downsample_box(x);
        const Image y = random_image(coarse_x.width(), coarse_x.height(), 3, std::uint64_t(w + 7 * h));
        Image adjoint_y(w, h, 3);
        downsample_box_adjoint(y, adjoint_y);
        const double lhs = inner_product(coarse_x, y), rhs = inner_product(x, adjoint_y);
        EXPECT_NEAR(lhs, rhs, 1e-5 * (1 + std::abs(lhs))) << w << "x" << h;
    }
}

// The exact-half path (every level of an even mip pyramid) must give the general area
// resize's bits: 0 + 0.25 a + 0.25 b + 0.25 c + 0.25 d in its order, and the adjoint one quarter
// added once to each fine value. Negative zeros included (0 + -0 is +0 in both).
TEST(ImageOps, ExactHalfBoxDownsampleAndAdjointKeepTheGeneralPathsBits) {
    for (const int channels : {1, 3, 4}) {
        Image x = random_image(10, 6, channels, std::uint64_t(40 + channels));
        for (float& v : x.values()) v = v * 7.0f - 3.5f;
        x.at(0, 0, 0) = -0.0f, x.at(1, 0, 0) = -0.0f, x.at(0, 1, 0) = -0.0f, x.at(1, 1, 0) = -0.0f;
        const Image down = downsample_box(x);
        ASSERT_EQ(down.width(), 5);
        ASSERT_EQ(down.height(), 3);
        for (int y = 0; y < 3; ++y)
            for (int px = 0; px < 5; ++px)
                for (int c = 0; c < channels; ++c) {
                    float expected = 0.0f;
                    for (int j = 0; j < 2; ++j)
                        for (int i = 0; i < 2; ++i) expected += (0.5f * 0.5f) * x.at(2 * px + i, 2 * y + j, c);
                    const float got = down.at(px, y, c);
                    EXPECT_EQ(std::memcmp(&got, &expected, sizeof(float)), 0) << px << "," << y << "," << c;
                }
        const Image g = random_image(5, 3, channels, std::uint64_t(50 + channels));
        Image fine = random_image(10, 6, channels, std::uint64_t(60 + channels));
        const Image before = fine;
        downsample_box_adjoint(g, fine);
        for (int y = 0; y < 6; ++y)
            for (int px = 0; px < 10; ++px)
                for (int c = 0; c < channels; ++c) {
                    const float expected = before.at(px, y, c) + (0.5f * 0.5f) * g.at(px / 2, y / 2, c);
                    const float got = fine.at(px, y, c);
                    EXPECT_EQ(std::memcmp(&got, &expected, sizeof(float)), 0) << px << "," << y << "," << c;
                }
    }
}

// In place, the convolution runs row by row and over column strips without a full-size buffer;
// every value must keep the two-buffer path's bits (float and double kernels, every addressing
// mode, rows longer than a strip and not a multiple of it).
TEST(ImageOps, InPlaceSeparableConvolutionKeepsTheBufferedBits) {
    const std::vector<float> tent = {0.25f, 0.5f, 0.25f}, wide = {0.1f, 0.2f, 0.4f, 0.2f, 0.1f};
    const std::vector<double> wide_double = {0.1, 0.2, 0.4, 0.2, 0.1};
    for (const auto& [w, h, c] : std::vector<std::array<int, 3>>{{97, 13, 4}, {5, 40, 3}, {300, 7, 1}, {1, 1, 2}})
        for (const Addressing mode : {Addressing::Border, Addressing::Clamp, Addressing::Wrap, Addressing::Mirror}) {
            const Image input = random_image(w, h, c, std::uint64_t(w * 7 + h + c), -2.0f, 3.0f);
            const auto check = [&](const auto& kernel, const char* name) {
                Image buffered(w, h, c), in_place = input;
                convolve_separable(input, buffered, kernel, mode);
                convolve_separable(in_place, in_place, kernel, mode);
                EXPECT_EQ(std::memcmp(buffered.data(), in_place.data(), buffered.values().size() * sizeof(float)), 0)
                    << w << "x" << h << "x" << c << " " << name << " mode " << int(mode);
            };
            check(tent, "tent");
            check(wide, "wide");
            check(wide_double, "wide double");
        }
}

TEST(ImageOps, AreaAndBilinearAdjointsAreTransposes) {
    const std::vector<std::array<int, 4>> cases{{13, 9, 4, 4}, {10, 7, 3, 7}, {5, 5, 8, 3}, {6, 4, 6, 4}};
    for (const auto& [sw, sh, dw, dh] : cases) {
        const Image x = random_image(sw, sh, 2, std::uint64_t(sw * 100 + dw));
        const Image y = random_image(dw, dh, 2, std::uint64_t(sh * 100 + dh));
        Image area_adjoint(sw, sh, 2);
        resize_area_adjoint(y, area_adjoint);
        EXPECT_NEAR(inner_product(resize_area(x, dw, dh), y), inner_product(x, area_adjoint), 1e-5) << sw << "x" << sh;
        EXPECT_NEAR(inner_product(resize_bilinear(x, dw, dh), y), inner_product(x, resize_bilinear_adjoint(y, sw, sh)), 1e-5)
            << sw << "x" << sh;
    }
}

TEST(ImageOps, HalfDownsampleRoundsUpAndAveragesWhatExists) {
    const Image image = coordinate_image(3, 3, 1);
    const Image down = downsample_half(image);
    ASSERT_EQ(down.width(), 2);
    ASSERT_EQ(down.height(), 2);
    EXPECT_FLOAT_EQ(down.at(0, 0, 0), (0 + 10 + 1 + 11) / 4.f);
    EXPECT_FLOAT_EQ(down.at(1, 0, 0), (20 + 21) / 2.f);  // last column alone
    EXPECT_FLOAT_EQ(down.at(1, 1, 0), 22.f);             // the corner pixel alone
}

TEST(ImageOps, SeparableConvolutionMatchesADirectSumInEveryMode) {
    // Radius 4 on a 7 x 3 image: the taps reach past the image more than once vertically.
    const Image image = random_image(7, 3, 2, 17);
    const std::vector<float> kernel = gaussian_kernel<float>(1.7f, 4);
    const std::vector<double> kernel_double = gaussian_kernel<double>(1.7, 4);
    for (Addressing mode : {Addressing::Clamp, Addressing::Wrap, Addressing::Mirror, Addressing::Border}) {
        Image out(7, 3, 2), out_double(7, 3, 2);
        convolve_separable(image, out, kernel, mode);
        convolve_separable(image, out_double, kernel_double, mode);
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 7; ++x)
                for (int c = 0; c < 2; ++c) {
                    double sum = 0;
                    for (int j = -4; j <= 4; ++j)
                        for (int i = -4; i <= 4; ++i) {
                            const int sx = address(x + i, 7, mode), sy = address(y + j, 3, mode);
                            if (sx < 0 || sy < 0) continue;
                            sum += kernel_double[std::size_t(i + 4)] * kernel_double[std::size_t(j + 4)] *
                                   image.at(sx, sy, c);
                        }
                    EXPECT_NEAR(out.at(x, y, c), sum, 1e-5) << int(mode) << " " << x << "," << y;
                    EXPECT_NEAR(out_double.at(x, y, c), sum, 1e-6) << int(mode) << " " << x << "," << y;
                }
        // In place gives the same bits.
        Image in_place = image;
        convolve_separable(in_place, in_place, kernel, mode);
        EXPECT_EQ(in_place.values(), out.values());
    }
}

TEST(ImageOps, ZeroPaddedConvolutionIsSelfAdjoint) {
    // Symmetric kernel, Border addressing: K = K^T (what the SSIM backward pass relies on).
    const Image x = random_image(9, 6, 3, 1), y = random_image(9, 6, 3, 2);
    const std::vector<float> kernel = gaussian_kernel<float>(1.5f, 5);
    Image kx(9, 6, 3), ky(9, 6, 3);
    convolve_separable(x, kx, kernel, Addressing::Border);
    convolve_separable(y, ky, kernel, Addressing::Border);
    EXPECT_NEAR(inner_product(kx, y), inner_product(x, ky), 1e-5);
}

TEST(ImageOps, ConvolutionOnAStridedView) {
    // The middle 4 columns of a wider image, filtered through a view, equal the same columns
    // copied out and filtered on their own.
    const Image wide = random_image(10, 5, 1, 8);
    Image part(4, 5, 1);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 4; ++x) part.at(x, y, 0) = wide.at(x + 3, y, 0);
    const std::vector<float> kernel = gaussian_kernel<float>(1.0f, 3);
    Image expected(4, 5, 1);
    convolve_separable(part, expected, kernel, Addressing::Mirror);
    Image out = wide;
    convolve_separable(ConstImageView(wide.pixel(3, 0), 4, 5, 1, 10), ImageView(out.pixel(3, 0), 4, 5, 1, 10), kernel,
                       Addressing::Mirror);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 10; ++x)
            EXPECT_EQ(out.at(x, y, 0), x >= 3 && x < 7 ? expected.at(x - 3, y, 0) : wide.at(x, y, 0));
}

TEST(ImageOps, GaussianKernelIsNormalisedAndSymmetric) {
    const std::vector<float> k = gaussian_kernel<float>(2.0f, 6);
    ASSERT_EQ(k.size(), 13u);
    double total = 0;
    for (float v : k) total += v;
    EXPECT_NEAR(total, 1.0, 1e-6);
    for (int i = 0; i < 6; ++i) EXPECT_EQ(k[std::size_t(i)], k[std::size_t(12 - i)]);
    EXPECT_EQ(gaussian_kernel<float>(2.0f, 6, false)[6], 1.0f);
}

TEST(ImageOps, SameResultsOnOneThreadAndMany) {
    const Image image = random_image(37, 29, 3, 5);
    const std::vector<float> kernel = gaussian_kernel<float>(2.5f, 8);
    const auto run = [&] {
        std::vector<Image> out{resize_bilinear(image, 16, 50), resize_bilinear_adjoint(image, 50, 40),
                               resize_area(image, 11, 9), downsample_box(image), downsample_half(image),
                               gaussian_blur_masked(image, Image(), 2.0f)};
        Image fine(74, 58, 3);
        downsample_box_adjoint(image, fine);
        out.push_back(fine);
        Image blurred(37, 29, 3);
        convolve_separable(image, blurred, kernel, Addressing::Mirror);
        out.push_back(blurred);
        return out;
    };
    const std::vector<Image> many = run();
    ThreadLimit one(1);
    const std::vector<Image> single = run();
    for (std::size_t i = 0; i < many.size(); ++i) EXPECT_EQ(many[i].values(), single[i].values()) << i;
}

TEST(ImageOps, EmptySizesAreRejected) {
    EXPECT_THROW(resize_bilinear(Image(4, 4, 1), 0, 4), Error);
    EXPECT_THROW(resize_area(Image(4, 4, 1), 3, 0), Error);
    EXPECT_THROW(resize_lanczos(Image(), 3, 3), Error);
    EXPECT_THROW(resize_bilinear_adjoint(Image(2, 2, 1), 0, 3), Error);
}
