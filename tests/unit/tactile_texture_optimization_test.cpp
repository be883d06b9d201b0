// Texture optimisation (Kwatra et al. 2005) behind `tdf tactile convert --synthesis optimize`.
#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/tactile/quilting.h>
#include <tdf/tactile/texture_optimization.h>

#include "unit/tactile_test_util.h"

using namespace tdf;
using tdf::test::synthetic_texture;

namespace {

TextureOptimizationOptions small_options() {
    TextureOptimizationOptions o;
    o.windows = {16, 8};
    o.iterations = {2};
    o.seed = 5;
    return o;
}

}  // namespace

TEST(TextureOptimization, SameSeedSameOutputOnOneAndTwoThreads) {
    const std::vector<Image> exemplars = {synthetic_texture(64, 1), synthetic_texture(56, 2)};
    const Image initial = synthetic_texture(96, 3);
    for (bool tileable : {false, true}) {
        TextureOptimizationOptions o = small_options();
        o.tileable = tileable;
        Image one, two;
        {
            ThreadLimit limit(1);
            one = optimize_texture(exemplars, {}, initial, o);
        }
        {
            ThreadLimit limit(2);
            two = optimize_texture(exemplars, {}, initial, o);
        }
        EXPECT_EQ(one.values(), two.values()) << "tileable " << tileable;
        o.seed = 6;
        EXPECT_NE(optimize_texture(exemplars, {}, initial, o).values(), one.values()) << "the seed has no effect";
    }
}

TEST(TextureOptimization, MovesANoiseStartTowardsTheExemplar) {
    // Stripes of period 8 along x; a random start becomes stripes: its rows correlate.
    Image stripes(64, 64, 1);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) stripes.at(x, y, 0) = std::sin(6.2831853f * float(x) / 8.0f);
    Image start(96, 96, 1);
    Rng rng(9);
    for (float& v : start.values()) v = rng.uniform(-1.0f, 1.0f);
    const Image out = optimize_texture({stripes}, {}, start, small_options());
    auto row_correlation = [](const Image& im) {  // mean correlation of each row with the next
        double sum = 0;
        for (int y = 0; y + 1 < im.height(); ++y) {
            double ab = 0, aa = 0, bb = 0;
            for (int x = 0; x < im.width(); ++x) {
                const double a = im.at(x, y, 0), b = im.at(x, y + 1, 0);
                ab += a * b, aa += a * a, bb += b * b;
            }
            sum += ab / std::sqrt(aa * bb + 1e-30);
        }
        return sum / (im.height() - 1);
    };
    EXPECT_LT(row_correlation(start), 0.9);
    EXPECT_GT(row_correlation(out), 0.95);
}

TEST(TextureOptimization, WindowsComeOnlyFromTheRegion) {
    // Texture on the left half, a constant on the right. A flat start matches the flat half
    // best, so without the mask flat areas survive; with it, none does.
    Image exemplar = synthetic_texture(96, 11);
    Image mask(96, 96, 1);
    for (int y = 0; y < 96; ++y)
        for (int x = 0; x < 96; ++x) {
            if (x >= 48) exemplar.at(x, y, 0) = 0.0f;
            mask.at(x, y, 0) = x < 48 ? 1.0f : 0.0f;
        }
    // Share of 4 x 4 cells of the output with (almost) no relief.
    auto flat_cells = [](const Image& im) {
        int flat = 0, cells = 0;
        for (int y = 0; y + 4 <= im.height(); y += 4)
            for (int x = 0; x + 4 <= im.width(); x += 4) {
                float lo = 1e9f, hi = -1e9f;
                for (int j = 0; j < 4; ++j)
                    for (int i = 0; i < 4; ++i) lo = std::min(lo, im.at(x + i, y + j, 0)), hi = std::max(hi, im.at(x + i, y + j, 0));
                flat += hi - lo < 1e-3f;
                ++cells;
            }
        return double(flat) / cells;
    };
    TextureOptimizationOptions o = small_options();
    o.min_coverage = 1.0f;
    const Image start(80, 80, 1, 0.0f);
    EXPECT_GT(flat_cells(optimize_texture({exemplar}, {}, start, o)), 0.5) << "the test needs a flat attractor";
    EXPECT_EQ(flat_cells(optimize_texture({exemplar}, {mask}, start, o)), 0.0);
}

TEST(TextureOptimization, BadOptionsAreErrors) {
    const Image e = synthetic_texture(32, 1);
    TextureOptimizationOptions o = small_options();
    o.iterations = {0};
    EXPECT_THROW(optimize_texture({e}, {}, e, o), Error);
    o.iterations = {2, 2, 2};  // more counts than the 2 window sides
    EXPECT_THROW(optimize_texture({e}, {}, e, o), Error);
    o.iterations = {};
    EXPECT_THROW(optimize_texture({e}, {}, e, o), Error);
    o = small_options();
    o.windows = {};
    EXPECT_THROW(optimize_texture({e}, {}, e, o), Error);
    o = small_options();
    o.windows = {2};
    EXPECT_THROW(optimize_texture({e}, {}, e, o), Error);
    o = small_options();
    EXPECT_THROW(optimize_texture({}, {}, e, o), Error);
    EXPECT_THROW(optimize_texture({e}, {Image(8, 8, 1)}, e, o), Error);
}

TEST(TextureOptimization, NoLinePatternFromTheWindowGrid) {
    // Grooves along y with faint relief along them (like the groove scan). The last blend takes
    // every pixel from one window; with windows every 2 px the source changed only between odd
    // and even rows, so odd rows stepped 2.4x more than even ones (an alternation the input
    // does not have). Windows at every pixel in the last blend leave no such pattern.
    Image exemplar = synthetic_texture(96, 21);
    for (int y = 0; y < 96; ++y)
        for (int x = 0; x < 96; ++x)
            exemplar.at(x, y, 0) = 3.0f * std::sin(6.2831853f * float(x) / 24.0f) + 0.02f * exemplar.at(x, y, 0);
    TextureOptimizationOptions o = small_options();
    const Image out = optimize_texture({exemplar}, {}, synthetic_texture(128, 22), o);
    double even = 0, odd = 0;  // |step| from row y to y + 1, summed over even / odd y
    for (int y = 0; y < out.height(); ++y)
        for (int x = 0; x < out.width(); ++x)
            (y % 2 ? odd : even) += std::abs(out.at(x, (y + 1) % out.height(), 0) - out.at(x, y, 0));
    RecordProperty("even_odd_row_steps", std::to_string(even / odd));
    EXPECT_NEAR(even / odd, 1.0, 0.15);
}

TEST(TextureOptimization, IterationsCountPerWindowSide) {
    // iterations[k] runs at windows[k]; a shorter list repeats its last value.
    const std::vector<Image> exemplars = {synthetic_texture(64, 1)};
    const Image initial = synthetic_texture(80, 3);
    TextureOptimizationOptions o = small_options();
    auto run = [&](std::vector<int> iterations) {
        o.iterations = std::move(iterations);
        return optimize_texture(exemplars, {}, initial, o).values();
    };
    const ImageValues two_two = run({2, 2});
    EXPECT_EQ(run({2}), two_two) << "one value is every side's";
    EXPECT_NE(run({3, 2}), two_two) << "the coarse side's count has no effect";
    EXPECT_NE(run({2, 3}), two_two) << "the fine side's count has no effect";
}
