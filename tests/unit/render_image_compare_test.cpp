#include <common/test_paths.h>
#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/render/folder_compare.h>
#include <tdf/render/image_compare.h>

#include <cmath>
#include <filesystem>
#include <limits>

using namespace tdf;

namespace {

std::vector<ExrLayer> two_layers(float albedo, float mask = 1.f) {
    Image a(8, 6, 3), m(8, 6, 1);
    for (float& v : a.values()) v = albedo;
    for (float& v : m.values()) v = mask;
    return {{"albedo", {"R", "G", "B"}, a}, {"mask", {"Y"}, m}};
}

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

}  // namespace

TEST(ImageCompare, IdenticalImagesHaveInfinitePsnrAndFiniteStatistics) {
    const auto a = two_layers(0.25f);
    const CompareResult r = compare_layers(a, a, {});
    EXPECT_TRUE(r.passed);
    EXPECT_TRUE(std::isinf(r.overall.psnr));
    EXPECT_EQ(r.overall.mean_error, 0.0);
    EXPECT_EQ(r.overall.rms_error, 0.0);
    ASSERT_EQ(r.layers.size(), 2u);
    EXPECT_EQ(r.layers[0].name, "albedo");
    EXPECT_TRUE(r.layers[0].passed);
}

TEST(ImageCompare, PerLayerRowsReportTheirOwnErrorAndPixel) {
    const auto a = two_layers(0.25f);
    auto b = a;
    b[0].image.at(5, 4, 1) = 0.75f;  // albedo.G differs by 0.5 at (5, 4)
    const CompareResult r = compare_layers(a, b, {});
    EXPECT_FALSE(r.passed);
    EXPECT_FALSE(r.layers[0].passed);
    EXPECT_TRUE(r.layers[1].passed);
    EXPECT_DOUBLE_EQ(r.layers[0].stats.max_error, 0.5);
    EXPECT_EQ(r.layers[0].stats.max_x, 5);
    EXPECT_EQ(r.layers[0].stats.max_y, 4);
    EXPECT_EQ(r.layers[0].failed_pixels, 1u);
    EXPECT_NEAR(r.layers[0].fail_percent, 100.0 / 48.0, 1e-12);
    // RMS over the 144 albedo values: sqrt(0.25 / 144); PSNR 20 log10(1 / rms).
    EXPECT_NEAR(r.layers[0].stats.rms_error, std::sqrt(0.25 / 144), 1e-12);
    EXPECT_NEAR(r.layers[0].stats.psnr, 20 * std::log10(1 / std::sqrt(0.25 / 144)), 1e-9);
}

TEST(ImageCompare, NonFiniteValuesFailUnlessAllowed) {
    for (const auto& [va, vb] : {std::pair{kNan, kNan}, std::pair{kInf, kInf}, std::pair{-kInf, -kInf}}) {
        auto a = two_layers(0.5f), b = two_layers(0.5f);
        a[0].image.at(2, 3, 0) = va;
        b[0].image.at(2, 3, 0) = vb;
        const CompareResult strict = compare_layers(a, b, {});
        EXPECT_FALSE(strict.passed) << va;
        EXPECT_EQ(strict.overall.nonfinite, 1u);
        EXPECT_EQ(strict.overall.nonfinite_x, 2);
        EXPECT_EQ(strict.overall.nonfinite_y, 3);
        EXPECT_TRUE(std::isfinite(strict.overall.mean_error));
        EXPECT_TRUE(std::isfinite(strict.overall.rms_error));
        CompareOptions allow;
        allow.allow_nonfinite = true;
        EXPECT_TRUE(compare_layers(a, b, allow).passed) << va;
    }
    // Different non-finite values, or one finite, fail even when allowed.
    auto a = two_layers(0.5f), b = two_layers(0.5f);
    a[0].image.at(1, 1, 2) = kInf;
    b[0].image.at(1, 1, 2) = -kInf;
    CompareOptions allow;
    allow.allow_nonfinite = true;
    EXPECT_FALSE(compare_layers(a, b, allow).passed);
    b[0].image.at(1, 1, 2) = kNan;
    EXPECT_FALSE(compare_layers(a, b, allow).passed);
    b[0].image.at(1, 1, 2) = 0.5f;
    EXPECT_FALSE(compare_layers(a, b, allow).passed);
}

TEST(ImageCompare, InvalidOptionsAreRejected) {
    const auto a = two_layers(0.5f);
    for (auto set : {+[](CompareOptions& o) { o.fail = kNan; },
                     +[](CompareOptions& o) { o.fail = -1; },
                     +[](CompareOptions& o) { o.fail = kInf; },
                     +[](CompareOptions& o) { o.failpercent = kNan; },
                     +[](CompareOptions& o) { o.failpercent = 101; },
                     +[](CompareOptions& o) { o.hardfail = kNan; },
                     +[](CompareOptions& o) { o.hardfail = -0.5f; },
                     +[](CompareOptions& o) { o.erode_mask = -1; }}) {
        CompareOptions o;
        set(o);
        EXPECT_THROW(validate_compare_options(o), Error);
        EXPECT_THROW(compare_layers(a, a, o), Error);
    }
    CompareOptions ok;
    ok.hardfail = kInf;
    EXPECT_NO_THROW(validate_compare_options(ok));
}

TEST(FolderCompare, PairsFilesAndLayersAndNeverPassesByMistake) {
    namespace fs = std::filesystem;
    const fs::path root = fs::path(tdf::test::scratch_dir()) / "folder_compare";
    fs::remove_all(root);
    const std::string a = (root / "a").string(), b = (root / "b").string();
    ensure_folder(a + "/sub");
    ensure_folder(b + "/sub");
    // Empty folders prove nothing.
    EXPECT_FALSE(compare_folders(a, b, {}).passed);

    write_exr(a + "/view_000.exr", two_layers(0.5f));
    write_exr(b + "/view_000.exr", two_layers(0.5f));
    write_exr(a + "/sub/view_001.exr", two_layers(0.5f));
    write_exr(b + "/sub/view_001.exr", two_layers(0.5f));
    FolderComparison r = compare_folders(a, b, {});
    EXPECT_TRUE(r.passed);
    ASSERT_EQ(r.files.size(), 2u);
    EXPECT_EQ(r.files[1].path, "view_000.exr");
    EXPECT_EQ(r.files[0].path, "sub/view_001.exr");
    EXPECT_EQ(r.totals.rows, 4u);  // 2 files x (albedo, mask)
    EXPECT_TRUE(std::isinf(r.totals.min_psnr));

    // A file only in A is a failure unless allowed; the same for B.
    write_exr(a + "/view_002.exr", two_layers(0.5f));
    r = compare_folders(a, b, {});
    EXPECT_FALSE(r.passed);
    EXPECT_EQ(r.totals.missing, 1u);
    FolderCompareOptions allow;
    allow.allow_missing = true;
    EXPECT_TRUE(compare_folders(a, b, allow).passed);
    write_exr(b + "/view_003.exr", two_layers(0.5f));
    EXPECT_FALSE(compare_folders(a, b, allow).passed);
    allow.allow_extra = true;
    EXPECT_TRUE(compare_folders(a, b, allow).passed);

    // A layer missing in B fails the file; a differing pixel fails its row and writes a diff.
    auto one = two_layers(0.5f);
    one.pop_back();
    write_exr(b + "/sub/view_001.exr", one);
    r = compare_folders(a, b, allow);
    EXPECT_TRUE(r.passed);  // allow_missing covers layers too
    FolderCompareOptions strict;
    strict.diff_folder = (root / "diff").string();
    auto changed = two_layers(0.5f);
    changed[0].image.at(0, 0, 0) = kNan;
    write_exr(b + "/view_000.exr", changed);
    r = compare_folders(a, b, strict);
    EXPECT_FALSE(r.passed);
    const FileComparison& f = r.files[1];
    ASSERT_EQ(f.path, "view_000.exr");
    EXPECT_FALSE(f.passed);
    EXPECT_EQ(f.result.layers[0].stats.nonfinite, 1u);
    EXPECT_TRUE(f.result.layers[1].passed);
    EXPECT_TRUE(fs::exists(root / "diff" / "view_000.diff.exr"));
    EXPECT_TRUE(std::isfinite(r.totals.overall.mean_error));

    // Size mismatch is recorded per file, not thrown.
    Image small(4, 4, 3);
    write_exr(b + "/view_000.exr", std::vector<ExrLayer>{{"albedo", {"R", "G", "B"}, small}});
    r = compare_folders(a, b, allow);
    EXPECT_EQ(r.totals.size_mismatch, 1u);
    EXPECT_FALSE(r.passed);
    EXPECT_THROW(compare_folders(a, (root / "absent").string(), {}), Error);
}
