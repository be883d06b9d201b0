#include <tdf/core/error.h>
#include <tdf/io/image_io.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace tdf;

namespace {
Image ramp(int w, int h, int c) {
    Image img(w, h, c);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < c; ++k) img.at(x, y, k) = float((x + 3 * y + 7 * k) % 256) / 255.0f;
    return img;
}
}  // namespace

TEST(ImageIo, Png8And16RoundTripExactly) {
    const Image img = ramp(17, 9, 3);
    const std::string p8 = test::scratch_dir() + "/rt8.png", p16 = test::scratch_dir() + "/rt16.png";
    write_png(p8, img, 8, Quantize::Round);
    write_png(p16, img, 16, Quantize::Round);
    const Image r8 = read_image(p8), r16 = read_image(p16);
    ASSERT_EQ(r8.width(), 17);
    ASSERT_EQ(r8.channels(), 3);
    for (std::size_t i = 0; i < img.values().size(); ++i) {
        EXPECT_NEAR(r8.values()[i], img.values()[i], 0.5f / 255.0f);
        EXPECT_NEAR(r16.values()[i], img.values()[i], 0.5f / 65535.0f);
    }
}

TEST(ImageIo, TruncationMatchesReferenceCast) {
    Image img(1, 1, 1, 0.999f);  // 254.745 -> 254 truncated, 255 rounded
    const std::string p = test::scratch_dir() + "/trunc.png";
    write_png(p, img, 8, Quantize::Truncate);
    EXPECT_FLOAT_EQ(read_image(p).at(0, 0, 0), 254.0f / 255.0f);
}

TEST(ImageIo, MultiLayerExrKeepsNamesAndValues) {
    const Image albedo = ramp(8, 5, 3), depth = ramp(8, 5, 1);
    const std::string p = test::scratch_dir() + "/layers.exr";
    write_exr(p, {{"albedo", {"R", "G", "B"}, albedo}, {"depth", {"Z"}, depth}});
    const auto layers = read_exr_layers(p);
    ASSERT_EQ(layers.size(), 2u);
    EXPECT_EQ(layers[0].name, "albedo");
    EXPECT_EQ(layers[0].channel_names, (std::vector<std::string>{"R", "G", "B"}));
    EXPECT_EQ(layers[1].name, "depth");
    EXPECT_EQ(layers[0].image.values(), albedo.values());
    EXPECT_EQ(layers[1].image.values(), depth.values());
}

TEST(ImageIo, HalfExrStoresHalfPrecisionValues) {
    const Image img = ramp(8, 5, 3);
    const std::string p = test::scratch_dir() + "/half.exr";
    write_exr(p, img, ExrPixelType::Half);
    const Image back = read_image(p);
    ASSERT_EQ(back.values().size(), img.values().size());
    for (std::size_t i = 0; i < img.values().size(); ++i)
        EXPECT_NEAR(back.values()[i], img.values()[i], 1e-3f * std::max(1.0f, img.values()[i]));
    EXPECT_LT(std::filesystem::file_size(p), 2000u);
}

TEST(ImageIo, BadFilesGiveErrorsNamingTheFile) {
    const std::string missing = test::scratch_dir() + "/does_not_exist.png";
    EXPECT_THROW(read_image(missing), Error);
    const std::string truncated = test::scratch_dir() + "/truncated.png";
    write_png(truncated, ramp(64, 64, 3));
    std::filesystem::resize_file(truncated, 100);
    try {
        read_image(truncated);
        FAIL() << "truncated PNG accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("truncated.png"), std::string::npos) << e.what();
    }
    const std::string text = test::scratch_dir() + "/not_an_image.png";
    std::ofstream(text) << "hello world";
    EXPECT_THROW(read_image(text), Error);
}
