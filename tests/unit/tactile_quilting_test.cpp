#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/tactile/height_input.h>
#include <tdf/tactile/pipeline.h>
#include <tdf/tactile/quilting.h>

#include <cmath>
#include <filesystem>

#include "common/test_paths.h"
#include "unit/tactile_test_util.h"

using namespace tdf;
using tdf::test::error_of;
using tdf::test::synthetic_texture;

namespace {

const std::string kStrawberry = "tactile/gelsight_raw/strawberry_00000_gxgy.npz";

// Mean squared difference between neighbouring lines i and i+1 (wrapping around): columns
// when `columns`, else rows. A seam shows up as a line pair far above the typical one.
double line_step(const Image& image, bool columns, int i) {
    const int lines = columns ? image.width() : image.height(),
              length = columns ? image.height() : image.width();
    const int next = (i + 1) % lines;
    double sum = 0;
    for (int k = 0; k < length; ++k) {
        const double d = columns ? double(image.at(next, k, 0)) - image.at(i, k, 0)
                                 : double(image.at(k, next, 0)) - image.at(k, i, 0);
        sum += d * d;
    }
    return sum / length;
}

}  // namespace

TEST(Quilting, SameSeedSameOutputOnOneAndTwoThreads) {
    const std::vector<Image> exemplars = {synthetic_texture(72, 1), synthetic_texture(64, 2)};
    QuiltOptions options;
    options.size = 150;
    options.block = 16;
    options.seed = 7;
    for (bool tileable : {false, true}) {
        options.tileable = tileable;
        options.feather = tileable ? 2 : 0;  // blending reads placed pixels too
        Image one, two;
        {
            ThreadLimit limit(1);
            one = quilt(exemplars, options).image;
        }
        {
            ThreadLimit limit(2);
            two = quilt(exemplars, options).image;
        }
        EXPECT_EQ(one.values(), two.values()) << "tileable " << tileable;
        options.seed = 8;
        EXPECT_NE(quilt(exemplars, options).image.values(), one.values()) << "the seed has no effect";
        options.seed = 7;
    }
}

TEST(Quilting, OutputSizesAndCopiesExemplarValues) {
    const Image exemplar = synthetic_texture(64, 3, 3);
    QuiltOptions options;
    options.size = 100;
    options.block = 20;
    const QuiltResult plain = quilt({exemplar}, options);
    EXPECT_EQ(plain.image.width(), 100);
    EXPECT_EQ(plain.image.channels(), 3);
    options.tileable = true;
    EXPECT_EQ(quilt_output_side(options), 100);  // stride 10
    options.size = 1024;
    options.block = 40;
    EXPECT_EQ(quilt_output_side(options), 1020);
    // Every output pixel is a copy of some exemplar pixel (quilting never blends).
    const Image& out = plain.image;
    for (int y = 0; y < out.height(); y += 7)
        for (int x = 0; x < out.width(); x += 7) {
            bool found = false;
            for (std::size_t p = 0; p < exemplar.pixel_count() && !found; ++p)
                found = exemplar.data()[3 * p] == out.at(x, y, 0) &&
                        exemplar.data()[3 * p + 1] == out.at(x, y, 1);
            ASSERT_TRUE(found) << x << "," << y;
        }
}

TEST(Quilting, BoundaryCutsAreFarBetterThanRandomPlacement) {
    QuiltOptions options;
    options.size = 256;
    options.block = 24;
    const QuiltResult result = quilt({synthetic_texture(96, 4)}, options);
    RecordProperty("cut_error", std::to_string(result.stats.mean_cut_error));
    RecordProperty("random_error", std::to_string(result.stats.mean_random_error));
    EXPECT_GT(result.stats.mean_random_error, 0.0);
    EXPECT_LT(result.stats.mean_cut_error, 0.1 * result.stats.mean_random_error);
}

TEST(Quilting, TileableOutputHasNoWrapSeam) {
    QuiltOptions options;
    options.size = 160;
    options.block = 20;
    options.tileable = true;
    const Image exemplar = synthetic_texture(80, 5);
    const Image tiled = quilt({exemplar}, options).image;
    options.tileable = false;
    const Image plain = quilt({exemplar}, options).image;
    // Typical step between neighbouring columns/rows inside vs. across the wrap-around.
    auto interior = [](const Image& image, bool columns) {
        double sum = 0;
        const int n = (columns ? image.width() : image.height()) - 1;
        for (int i = 0; i < n; ++i) sum += line_step(image, columns, i);
        return sum / n;
    };
    for (bool columns : {true, false}) {
        const double wrap_tiled = line_step(tiled, columns, (columns ? tiled.width() : tiled.height()) - 1);
        const double wrap_plain = line_step(plain, columns, (columns ? plain.width() : plain.height()) - 1);
        const double inside = interior(tiled, columns);
        RecordProperty(columns ? "wrap_columns_ratio" : "wrap_rows_ratio",
                       std::to_string(wrap_tiled / inside));
        EXPECT_LT(wrap_tiled, 2.0 * inside) << (columns ? "columns" : "rows");
        EXPECT_GT(wrap_plain, 4.0 * interior(plain, columns)) << "the criterion cannot see a seam";
    }
}

TEST(Quilting, BadInputGivesClearErrors) {
    QuiltOptions options;
    options.block = 40;
    options.size = 128;
    const std::string small = error_of([&] { quilt({Image(30, 64, 1)}, options, {"small.exr"}); });
    EXPECT_NE(small.find("small.exr"), std::string::npos) << small;
    EXPECT_NE(small.find("smaller than the block size 40"), std::string::npos) << small;
    Image nan = synthetic_texture(64, 6);
    nan.at(5, 5, 0) = std::nanf("");
    EXPECT_NE(error_of([&] { quilt({nan}, options, {"nan.exr"}); }).find("nan.exr"), std::string::npos);
    EXPECT_NE(error_of([&] {
                  quilt({Image(64, 64, 1), Image(64, 64, 3)}, options);
              }).find("channels"),
              std::string::npos);
    options.feather = 20;
    EXPECT_NE(error_of([&] { quilt({Image(64, 64, 1)}, options); }).find("--feather"), std::string::npos);
    options.feather = 0;
    options.overlap = 0.8f;
    EXPECT_NE(error_of([&] { quilt({Image(64, 64, 1)}, options); }).find("--overlap"), std::string::npos);
    // A constant exemplar is no error: every candidate matches exactly.
    options.overlap = 0.5f;
    const QuiltResult flat = quilt({Image(64, 64, 1, 0.25f)}, options);
    for (float v : flat.image.values()) ASSERT_EQ(v, 0.25f);
}

TEST(Quilting, StrawberryPatchQuiltsWithoutVisibleSeams) {
    TDF_REQUIRE_SHARED_DATA(kStrawberry);
    const HeightMap patch =
        extract_patch(load_height_input(test::shared_data_dir() + "/" + kStrawberry), PatchOptions{});
    QuiltOptions options;
    options.size = 400;
    options.block = 40;
    options.tileable = true;
    QuiltStats stats;
    const HeightMap quilted = quilt_height_maps({patch}, options, &stats);
    EXPECT_EQ(quilted.height.width(), 400);
    EXPECT_FLOAT_EQ(quilted.mm_per_pixel, patch.mm_per_pixel);
    RecordProperty("cut_error_mm2", std::to_string(stats.mean_cut_error));
    RecordProperty("random_error_mm2", std::to_string(stats.mean_random_error));
    EXPECT_LT(stats.mean_cut_error, 0.05 * stats.mean_random_error);
}

TEST(Quilting, MinContrastStopsFlatAreasFromGrowing) {
    // Textured except for a flat bottom-right quadrant: plain Efros-Freeman grows that flat
    // quadrant, since flat blocks match flat overlaps best.
    Image exemplar = synthetic_texture(96, 9);
    for (int y = 48; y < 96; ++y)
        for (int x = 48; x < 96; ++x) exemplar.at(x, y, 0) = 0.0f;
    auto flat_fraction = [](const Image& image) {  // share of 16x16 windows without texture
        int flat = 0, windows = 0;
        for (int y = 0; y + 16 <= image.height(); y += 16)
            for (int x = 0; x + 16 <= image.width(); x += 16, ++windows) {
                double sum = 0, sum2 = 0;
                for (int j = 0; j < 16; ++j)
                    for (int i = 0; i < 16; ++i)
                        sum += image.at(x + i, y + j, 0),
                            sum2 += double(image.at(x + i, y + j, 0)) * image.at(x + i, y + j, 0);
                flat += std::sqrt(std::max(sum2 / 256 - (sum / 256) * (sum / 256), 0.0)) < 0.05;
            }
        return double(flat) / windows;
    };
    QuiltOptions options;
    options.size = 320;
    options.block = 24;
    const double plain = flat_fraction(quilt({exemplar}, options).image);
    options.min_contrast = 0.5f;
    const double guarded = flat_fraction(quilt({exemplar}, options).image);
    RecordProperty("flat_plain", std::to_string(plain));
    RecordProperty("flat_min_contrast", std::to_string(guarded));
    EXPECT_GT(plain, 0.3);
    EXPECT_LT(guarded, 0.05);
}

TEST(Quilting, FeatheringRemovesTheStepsOfHardCuts) {
    TDF_REQUIRE_SHARED_DATA(kStrawberry);
    const HeightMap patch =
        extract_patch(load_height_input(test::shared_data_dir() + "/" + kStrawberry), PatchOptions{});
    // Mean squared Laplacian: the high-frequency energy a normal map shows. Hard cuts add steps
    // that the exemplar does not have; feathering turns them into ramps.
    auto roughness = [](const Image& image) {
        double sum = 0;
        for (int y = 1; y + 1 < image.height(); ++y)
            for (int x = 1; x + 1 < image.width(); ++x) {
                const double l = 4.0 * image.at(x, y, 0) - image.at(x - 1, y, 0) - image.at(x + 1, y, 0) -
                                 image.at(x, y - 1, 0) - image.at(x, y + 1, 0);
                sum += l * l;
            }
        return sum / (double(image.width() - 2) * double(image.height() - 2));
    };
    QuiltOptions options;
    options.size = 400;
    options.min_contrast = 0.5f;
    const double exemplar = roughness(patch.height);
    const double hard = roughness(quilt({patch.height}, options).image) / exemplar;
    options.feather = 2;
    const double feathered = roughness(quilt({patch.height}, options).image) / exemplar;
    RecordProperty("roughness_ratio_hard", std::to_string(hard));
    RecordProperty("roughness_ratio_feather2", std::to_string(feathered));
    EXPECT_GT(hard, 1.5);
    EXPECT_LT(feathered, 1.25);
}

TEST(Quilting, NoLinesAlongTheBlockEdges) {
    // Mean |step| between neighbouring lines, averaged per position within the stride: a cut
    // that ends at a block's edge, or a feather ramp cut off there, steps every stride lines.
    // Before cuts priced the pixel pair they separate and their free ends (and feathering read
    // past the block), the block edges' lines stepped 1.3-1.7x the mean on the shared samples
    // (this texture: 1.42x columns with feathering).
    HeightMap patch;
    patch.height = synthetic_texture(128, 14);
    patch.mm_per_pixel = 0.1f;
    for (const bool tileable : {false, true})
        for (const int feather : {0, 2}) {
            QuiltOptions options;
            options.size = 640;
            options.block = 40;
            options.tileable = tileable, options.min_contrast = 0.5f, options.feather = feather;
            const Image quilted = quilt({patch.height}, options).image;
            const int stride = 20;
            for (const bool columns : {true, false}) {
                std::vector<double> step(stride, 0.0);
                std::vector<int> count(stride, 0);
                const int lines = columns ? quilted.width() : quilted.height();
                const int length = columns ? quilted.height() : quilted.width();
                for (int i = 0; i + 1 < lines; ++i)
                    for (int k = 0; k < length; ++k) {
                        step[std::size_t(i % stride)] += std::abs(
                            columns ? double(quilted.at(i + 1, k, 0)) - quilted.at(i, k, 0)
                                    : double(quilted.at(k, i + 1, 0)) - quilted.at(k, i, 0));
                        ++count[std::size_t(i % stride)];
                    }
                double mean = 0, worst = 0;
                for (int p = 0; p < stride; ++p) mean += step[std::size_t(p)] / count[std::size_t(p)] / stride;
                for (int p = 0; p < stride; ++p) worst = std::max(worst, step[std::size_t(p)] / count[std::size_t(p)] / mean);
                RecordProperty(std::string("worst_line_") + (columns ? "columns" : "rows") +
                                   (tileable ? "_tileable" : "") + "_feather" + std::to_string(feather),
                               std::to_string(worst));
                EXPECT_LT(worst, 1.15) << (columns ? "columns" : "rows") << ", tileable " << tileable
                                       << ", feather " << feather;
            }
        }
}
