#include "common/test_images.h"
#include <tdf/core/error.h>
#include <tdf/core/rng.h>
#include <tdf/render/resample.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>

using namespace tdf;

namespace {
using test::inner_product;
using test::random_image;
}  // namespace

TEST(Resample, MatchesPyTorchAlignCornersFalse) {
    // 1-D along x: 4 -> 2 averages pairs (source 0.5 and 2.5).
    Image src(4, 1, 1);
    for (int x = 0; x < 4; ++x) src.at(x, 0, 0) = float(x * x);
    const Image down = downsample_bilinear(src, 2, 1);
    EXPECT_FLOAT_EQ(down.at(0, 0, 0), 0.5f);
    EXPECT_FLOAT_EQ(down.at(1, 0, 0), 6.5f);
    // 2 -> 4: sources -0.25 (clamped to 0), 0.25, 0.75, 1.25 (neighbour clamped).
    Image two(2, 1, 1);
    two.at(0, 0, 0) = 0;
    two.at(1, 0, 0) = 4;
    const Image up = downsample_bilinear(two, 4, 1);
    EXPECT_FLOAT_EQ(up.at(0, 0, 0), 0.f);
    EXPECT_FLOAT_EQ(up.at(1, 0, 0), 1.f);
    EXPECT_FLOAT_EQ(up.at(2, 0, 0), 3.f);
    EXPECT_FLOAT_EQ(up.at(3, 0, 0), 4.f);
    // SSAA case 768 -> 512 (s = 1.5): destination 1 samples 1.75.
    Image ramp(768, 2, 1);
    for (int x = 0; x < 768; ++x) ramp.at(x, 0, 0) = ramp.at(x, 1, 0) = float(x);
    EXPECT_FLOAT_EQ(downsample_bilinear(ramp, 512, 2).at(1, 0, 0), 1.75f);
}

TEST(Resample, AdjointIsTheExactTranspose) {
    for (const auto& [sw, sh, dw, dh] : {std::array{768, 520, 512, 344}, std::array{9, 7, 4, 3},
                                         std::array{3, 5, 8, 11}, std::array{16, 16, 16, 16}}) {
        const Image x = random_image(sw, sh, 3, 1);
        const Image y = random_image(dw, dh, 3, 2);
        const double lhs = inner_product(downsample_bilinear(x, dw, dh), y);
        const double rhs = inner_product(x, downsample_bilinear_adjoint(y, sw, sh));
        EXPECT_NEAR(lhs, rhs, 1e-6 * (std::abs(lhs) + 1)) << sw << "x" << sh << " -> " << dw << "x" << dh;
    }
}

TEST(Resample, ZeroSizeIsAnError) {
    EXPECT_THROW(downsample_bilinear(Image(4, 4, 1), 0, 4), Error);
}
