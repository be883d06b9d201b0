#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/contact_mask.h>
#include <tdf/tactile/high_pass.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/npy_reader.h>
#include <tdf/tactile/pipeline.h>
#include <tdf/tactile/poisson.h>
#include <tdf/tactile/resample.h>
#include <tdf/tactile/tactile_map.h>

#include <cmath>
#include <filesystem>

#include "common/test_paths.h"
#include "unit/tactile_test_util.h"

using namespace tdf;
using tdf::test::correlation;

namespace {

const std::string kStrawberry = "tactile/gelsight_raw/strawberry_00000_gxgy.npz";
const std::string kSamples = "tactile/texture_samples";
constexpr double kPi = 3.14159265358979323846;

Image wave(int w, int h, double cycles_x, double cycles_y) {
    Image image(w, h, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            image.at(x, y, 0) = float(std::sin(2 * kPi * (cycles_x * x / w + cycles_y * y / h)));
    return image;
}

Image array_image(const NpyArray& array) {
    Image image(int(array.shape[1]), int(array.shape[0]), 1);
    for (std::size_t i = 0; i < array.values.size(); ++i) image.data()[i] = float(array.values[i]);
    return image;
}

}  // namespace

TEST(HighPass, FftBlockRemovesLowAndKeepsHighFrequencies) {
    // 3 cycles across lies inside the reference's block [-5, 5); 20 cycles lies outside.
    const Image low = wave(64, 48, 3, 0), high = wave(64, 48, 20, 0);
    Image sum(64, 48, 1);
    for (std::size_t i = 0; i < sum.values().size(); ++i)
        sum.values()[i] = low.values()[i] + high.values()[i];
    const Image filtered = high_pass_fft_block(sum, 5);
    EXPECT_GT(correlation(filtered, high), 0.9999);
    EXPECT_FLOAT_EQ(*std::min_element(filtered.values().begin(), filtered.values().end()), 0.0f);
    // The bin -t of the asymmetric block passes at half amplitude (spec 6.2 step 2).
    const Image edge = high_pass_fft_block(wave(64, 48, 5, 0), 5);
    const auto [lo, hi] = std::minmax_element(edge.values().begin(), edge.values().end());
    EXPECT_NEAR(*hi - *lo, 1.0f, 1e-3f);  // a unit sine has range 2; half of it survives
}

TEST(HighPass, GaussianCutoffIsInMillimetres) {
    // Wavelength 0.5 mm passes, 8 mm is suppressed, at 0.1 mm per pixel with a 2 mm cut-off.
    const Image fine = wave(160, 160, 32, 0), coarse = wave(160, 160, 2, 0);
    auto range = [](const Image& image) {  // away from the mirrored borders (3 sigma = 12 px)
        float lo = 1e30f, hi = -1e30f;
        for (int x = 20; x < 140; ++x)
            lo = std::min(lo, image.at(x, 80, 0)), hi = std::max(hi, image.at(x, 80, 0));
        return hi - lo;
    };
    EXPECT_GT(range(high_pass_gaussian(fine, 2.0f, 0.1f)), 1.9f);
    // ISO Gaussian: 8 mm passes exp(-pi (0.4697 * 2 / 8)^2) = 0.957 through the low-pass, so
    // the high-pass keeps 4.3% of the amplitude.
    EXPECT_NEAR(range(high_pass_gaussian(coarse, 2.0f, 0.1f)), 2 * 0.043f, 0.01f);
}

TEST(ContactMask, CropsTheLargestContactSquare) {
    Image height(60, 40, 1, 0.0f);
    for (int y = 10; y < 30; ++y)
        for (int x = 5; x < 45; ++x) height.at(x, y, 0) = 1.0f;  // 40 x 20 contact
    height.at(55, 35, 0) = 2.0f;                                 // a speck: smaller component
    const ContactRegion region = find_contact_region(height, 0.5f, "test");
    // Dilated bbox x 3..46, y 8..31 (44 x 24) -> square 24 trimmed symmetrically -> even side 24.
    EXPECT_EQ(region.side, 24);
    EXPECT_EQ(region.y, 8);
    EXPECT_EQ(region.x, 3 + (44 - 24) / 2);
    EXPECT_EQ(region.mask.at(55, 35, 0), 0.0f);
    EXPECT_EQ(region.mask.at(20, 20, 0), 1.0f);
    try {
        find_contact_region(Image(10, 10, 1, 0.1f), 0.5f, "flat.npz");
        FAIL() << "no error for an empty contact mask";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("flat.npz"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("empty contact mask"), std::string::npos);
    }
}

TEST(NormalMap, MatchesTheReferenceFormulaAndEncoding) {
    // A ramp rising to the right by 0.1 per pixel with gain 2: slope 0.2, n = (-0.2, 0, 1)/|.|.
    Image ramp(8, 6, 1);
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 8; ++x) ramp.at(x, y, 0) = 0.1f * x + 0.05f * y;
    const Image n = normals_from_height(ramp, 2.0f);
    const float gy = 0.1f;  // heights grow downwards, so the surface faces up-image: +y
    const float len = std::sqrt(0.04f + gy * gy + 1.0f);
    for (int x : {0, 3, 7}) {
        EXPECT_NEAR(n.at(x, 2, 0), -0.2f / len, 1e-6f);
        EXPECT_NEAR(n.at(x, 2, 1), gy / len, 1e-6f);
        EXPECT_NEAR(n.at(x, 2, 2), 1.0f / len, 1e-6f);
    }
    const std::string path = test::scratch_dir() + "/ramp_normal.png";
    write_normal_map(path, n, 0.085f, "ramp", 8);
    ImageMetadata metadata;
    const Image png = read_image(path, metadata);
    EXPECT_EQ(png.at(3, 2, 0) * 255.0f, std::floor((-0.2f / len * 0.5f + 0.5f) * 255.0f));  // spec 6.4 step 5
    EXPECT_EQ(metadata.at("tdf:mm_per_pixel"), "0.085");
}

TEST(TactileMap, DecodesLikeTheReferenceAndKeepsTheScale) {
    Image encoded(4, 3, 3);
    encoded.at(0, 0, 0) = 127.0f / 255.0f, encoded.at(1, 0, 0) = 128.0f / 255.0f, encoded.at(2, 0, 0) = 1.0f;
    const std::string path = test::scratch_dir() + "/decode.png";
    write_png(path, encoded, {{"tdf:mm_per_pixel", "0.05"}}, 8, Quantize::Round);
    const TactileMap map = load_tactile_map(path);
    EXPECT_NEAR(map.normals.at(0, 0, 0), -0.00392f, 1e-5f);  // spec 1.3
    EXPECT_NEAR(map.normals.at(1, 0, 0), 0.00392f, 1e-5f);
    EXPECT_EQ(map.normals.at(2, 0, 0), 1.0f);
    EXPECT_EQ(map.normals.at(3, 2, 2), -1.0f);
    EXPECT_FLOAT_EQ(map.mm_per_pixel, 0.05f);

    const std::string exr = test::scratch_dir() + "/decoded.exr";
    write_exr(exr, map.normals, {{"tdf:mm_per_pixel", "0.05"}});
    EXPECT_EQ(load_tactile_map(exr).normals.values(), map.normals.values());
    EXPECT_FLOAT_EQ(load_tactile_map(exr).mm_per_pixel, 0.05f);

    const std::string grey = test::scratch_dir() + "/grey.png";
    write_png(grey, Image(4, 4, 1, 0.5f));
    EXPECT_THROW(load_tactile_map(grey), Error);  // 1 channel
    Image grey_rgb(4, 4, 3, 0.2f);
    grey_rgb.at(1, 1, 0) = grey_rgb.at(1, 1, 1) = grey_rgb.at(1, 1, 2) = 0.7f;
    write_png(grey, grey_rgb);
    EXPECT_THROW(load_tactile_map(grey), Error);  // R = G = B: a height map
    write_png(grey, Image(4, 4, 3, 0.5f));
    EXPECT_NO_THROW(load_tactile_map(grey));  // constant: flat, fine
}

TEST(Pipeline, HeightMapsRoundTripWithMetadata) {
    HeightMap map;
    map.height = wave(16, 12, 2, 1);
    map.mm_per_pixel = 0.0425f;
    map.reference_scale_mm = 4.5f;
    map.source = "wave";
    const std::string path = test::scratch_dir() + "/height.exr";
    write_height_map(path, map);
    const HeightMap back = read_height_map(path);
    EXPECT_EQ(back.height.values(), map.height.values());
    EXPECT_FLOAT_EQ(back.mm_per_pixel, 0.0425f);
    EXPECT_FLOAT_EQ(back.reference_scale_mm, 4.5f);
    const HeightInput input = load_height_input(path);
    EXPECT_FLOAT_EQ(input.map.mm_per_pixel, 0.0425f);
    EXPECT_EQ(input.kind, "height image");
}

TEST(Pipeline, StrawberryPatchMatchesTheReferenceScale) {
    TDF_REQUIRE_SHARED_DATA(kStrawberry);
    PatchSteps steps;
    const HeightMap patch =
        extract_patch(load_height_input(test::shared_data_dir() + "/" + kStrawberry), PatchOptions{}, &steps);
    EXPECT_EQ(patch.height.width(), 256);
    EXPECT_EQ(patch.height.height(), 256);
    // Reference output Strawberry_texture_sample_scale.npy: 4.546645 (spec 6.2 step 8).
    EXPECT_NEAR(patch.reference_scale_mm, 4.546645f, 1e-4f);
    EXPECT_FALSE(steps.contact_mask.empty());
    EXPECT_GT(patch.mm_per_pixel, 0.07f);  // 0.085 mm x crop / 256
    EXPECT_LT(patch.mm_per_pixel, 0.085f);
    const Image normals = normal_map_from_height(patch);
    ASSERT_TRUE(normals.all_finite());
    for (std::size_t p = 0; p < normals.pixel_count(); p += 97) {
        const float* n = normals.data() + 3 * p;
        ASSERT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-4f);
    }
}

TEST(Pipeline, StrawberryGradientsIntegrateToItsDepth) {
    TDF_REQUIRE_SHARED_DATA(kStrawberry);
    const auto arrays = read_npz(test::shared_data_dir() + "/" + kStrawberry);
    const Image integrated = integrate_gradients(array_image(arrays.at("gx")), array_image(arrays.at("gy")));
    const Image dm = array_image(arrays.at("dm")), dm_zero = array_image(arrays.at("dm_zero"));
    // Measured: gx/gy integrate to the SDK's raw depth `dm_zero` (r = 0.94); `dm` (background
    // removed by the SDK) shares the fine texture only: r = 0.29 after a 2 mm Gaussian high-pass.
    const double raw = correlation(integrated, dm_zero);
    const double textured =
        correlation(high_pass_gaussian(integrated, 2.0f, 0.085f), high_pass_gaussian(dm, 2.0f, 0.085f));
    RecordProperty("corr_dm_zero", std::to_string(raw));
    RecordProperty("corr_dm_high_pass_2mm", std::to_string(textured));
    EXPECT_GT(raw, 0.9);
    EXPECT_GT(textured, 0.25);
}

TEST(Pipeline, AllNineTextureSamplesConvert) {
    TDF_REQUIRE_SHARED_DATA(kSamples);
    int converted = 0;
    for (const auto& entry : std::filesystem::directory_iterator(test::shared_data_dir() + "/" + kSamples)) {
        if (entry.path().extension() != ".png") continue;
        const std::string path = entry.path().string();
        const HeightInput input = load_height_input(path);
        EXPECT_EQ(input.kind, "normal map") << path;
        PatchOptions patch_options;
        patch_options.size = 0;  // keep 240 x 240 for the fidelity check below
        const HeightMap patch = extract_patch(input, patch_options);
        EXPECT_EQ(patch.reference_scale_mm, 0.0f) << "normal maps keep physical amplitude";
        QuiltOptions quilt_options;
        quilt_options.size = 200;
        quilt_options.tileable = true;
        const HeightMap quilted = quilt_height_maps({patch}, quilt_options);
        const Image normals = normal_map_from_height(quilted);
        ASSERT_TRUE(normals.all_finite()) << path;
        const std::string out = test::scratch_dir() + "/" + entry.path().stem().string() + "_normal.png";
        write_normal_map(out, normals, quilted.mm_per_pixel, path);
        EXPECT_FLOAT_EQ(load_tactile_map(out).mm_per_pixel, 0.0f) << "no size in the file: unknown";

        // Without filtering, integrating the sample and differentiating again gives back its
        // normals: the Poisson step loses only the non-integrable part.
        PatchOptions raw_options = patch_options;
        raw_options.high_pass = HighPass::None;
        raw_options.smooth = Toggle::Off;
        const Image again = normal_map_from_height(extract_patch(input, raw_options));
        const TactileMap original = load_tactile_map(path);
        Image ox(240, 240, 1), ax(240, 240, 1);
        for (std::size_t p = 0; p < ox.pixel_count(); ++p)
            ox.data()[p] = original.normals.data()[3 * p], ax.data()[p] = again.data()[3 * p];
        const double r = correlation(ox, ax);
        RecordProperty(entry.path().stem().string() + "_corr_x", std::to_string(r));
        EXPECT_GT(r, 0.8) << path;
        ++converted;
    }
    EXPECT_EQ(converted, 9);
}

TEST(Pipeline, FlatPatchAndEmptyContactGiveErrors) {
    HeightInput input;
    input.map.height = Image(32, 32, 1, 0.1f);
    input.map.mm_per_pixel = 0.085f;
    input.map.source = "flat.npz";
    input.capture = true;
    PatchOptions options;
    try {
        extract_patch(input, options);
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("flat.npz: empty contact mask"), std::string::npos) << e.what();
    }
    options.contact = Toggle::Off;
    EXPECT_THROW(extract_patch(input, options), Error);  // flat: nothing to texture
}

TEST(Resample, LanczosKeepsConstantsAndIsCentred) {
    const Image flat = resize_lanczos(Image(10, 10, 2, 0.5f), 23, 17);
    for (float v : flat.values()) ASSERT_NEAR(v, 0.5f, 1e-6f);
    // Enlarging a ramp 2x: output x samples source (x + 0.5) / 2 - 0.5 (pixel centres aligned);
    // Lanczos-4 reproduces a line to within 1.5% of a pixel step.
    Image ramp(16, 1, 1);
    for (int x = 0; x < 16; ++x) ramp.at(x, 0, 0) = float(x);
    const Image up = resize_lanczos(ramp, 32, 1);
    for (int x = 8; x < 24; ++x) EXPECT_NEAR(up.at(x, 0, 0), (x + 0.5f) * 0.5f - 0.5f, 0.015f);
    EXPECT_NEAR(up.at(15, 0, 0) + up.at(16, 0, 0), 15.0f, 1e-4f);  // symmetric about the centre
}

TEST(TactilePipeline, NonFiniteStrengthIsAnErrorNotABlackMap) {
    HeightMap map;
    map.height = Image(8, 8, 1, 0.f);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) map.height.at(x, y, 0) = 0.01f * float(x * y);
    map.mm_per_pixel = 0.1f;
    map.source = "ramp.exr";
    EXPECT_TRUE(normal_map_from_height(map, Amplitude::Physical, 1.f).all_finite());
    for (const float strength : {std::nanf(""), INFINITY, 0.f, -1.f}) {
        try {
            normal_map_from_height(map, Amplitude::Physical, strength);
            ADD_FAILURE() << "strength " << strength << " accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("ramp.exr"), std::string::npos) << e.what();
        }
    }
}
