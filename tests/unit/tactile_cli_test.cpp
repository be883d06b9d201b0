// End-to-end runs of the `tdf tactile` steps through the built binary.
#include <gtest/gtest.h>
#include <fmt/format.h>
#include <tdf/core/config.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/tactile_map.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>

#include "common/test_paths.h"
#include "unit/gelsight_plate.h"
#include "unit/tactile_unseen_inputs.h"

using namespace tdf;

namespace {

const std::string kStrawberry = "tactile/gelsight_raw/strawberry_00000_gxgy.npz";

struct CliRun {
    int status = -1;
    std::string output;  // stdout and stderr
};

CliRun run_tdf(const std::string& arguments) {
    CliRun run;
    const std::string command = std::string(TDF_BINARY_DIR) + "/tdf " + arguments + " 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return run;
    std::array<char, 512> buffer;
    while (std::fgets(buffer.data(), int(buffer.size()), pipe)) run.output += buffer.data();
    const int status = pclose(pipe);
    run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return run;
}

}  // namespace

#define TDF_REQUIRE_TDF_BINARY()                                                              \
    do {                                                                                      \
        if (!std::filesystem::exists(std::string(TDF_BINARY_DIR) + "/tdf"))                   \
            GTEST_SKIP() << "the tdf binary is not built (cmake --build build --target tdf)"; \
    } while (0)

TEST(TactileCli, StepsChainFromCaptureToNormalMap) {
    TDF_REQUIRE_TDF_BINARY();
    TDF_REQUIRE_SHARED_DATA(kStrawberry);
    const std::string capture = test::shared_data_dir() + "/" + kStrawberry;
    const std::string dir = test::scratch_dir() + "/cli";
    std::filesystem::create_directories(dir);
    CliRun run = run_tdf("tactile patch " + capture + " -o " + dir + "/patch.exr -q");
    ASSERT_EQ(run.status, 0) << run.output;
    run = run_tdf("tactile quilt " + dir + "/patch.exr -o " + dir + "/quilt.exr --size 200 --tileable -q");
    ASSERT_EQ(run.status, 0) << run.output;
    run = run_tdf("tactile normal " + dir + "/quilt.exr -o " + dir + "/normal.png --bits 16 --exr -q");
    ASSERT_EQ(run.status, 0) << run.output;
    const TactileMap map = load_tactile_map(dir + "/normal.png");
    EXPECT_EQ(map.normals.width(), 200);
    EXPECT_NEAR(map.mm_per_pixel, 0.0797f, 1e-4f);  // 0.085 mm x 240 px crop / 256 px patch
    const TactileMap exr = load_tactile_map(dir + "/normal.exr");
    for (std::size_t i = 0; i < exr.normals.values().size(); i += 101)
        ASSERT_NEAR(exr.normals.values()[i], map.normals.values()[i], 2.0f / 65535.0f + 1e-6f);

    run = run_tdf("tactile convert " + capture + " -o " + dir + "/convert.png --size 120 --steps-png " + dir +
                  "/steps");
    ASSERT_EQ(run.status, 0) << run.output;
    for (const char* step : {"0_input_normal",
                             "1_raw_height",
                             "2_region",
                             "2_contact_mask",
                             "3_high_pass",
                             "4_smoothed",
                             "5_patch",
                             "6_quilted",
                             "7_normal_map"})
        EXPECT_TRUE(std::filesystem::exists(dir + "/steps/" + step + ".png")) << step;
    // The material statistics: printed, in the metadata and beside the step PNGs.
    EXPECT_NE(run.output.find("mean detail tilt"), std::string::npos) << run.output;
    EXPECT_TRUE(std::filesystem::exists(dir + "/steps/8_statistics.json"));
    ImageMetadata metadata;
    read_image(dir + "/convert.png", metadata);
    ASSERT_TRUE(metadata.count("tdf:material"));
    EXPECT_NE(metadata.at("tdf:material").find("\"tilt_ratio\""), std::string::npos);

    // Height steps also write PNG previews that read back in mm (issue 16).
    run = run_tdf("tactile patch " + capture + " -o " + dir + "/patch.png -q");
    ASSERT_EQ(run.status, 0) << run.output;
    run = run_tdf("tactile quilt " + dir + "/patch.png -o " + dir + "/quilt_from_png.exr --size 120 -q");
    ASSERT_EQ(run.status, 0) << run.output;
    run = run_tdf("tactile patch " + capture + " -o " + dir + "/patch.tif -q");
    EXPECT_EQ(run.status, 1) << run.output;
}

TEST(TactileCli, UnknownSizeGivesOneWarning) {
    TDF_REQUIRE_TDF_BINARY();
    TDF_REQUIRE_SHARED_DATA("tactile/texture_samples/Potato_00000.png");
    const std::string sample = test::shared_data_dir() + "/tactile/texture_samples/Potato_00000.png";
    const std::string out = test::scratch_dir() + "/potato_normal.png";
    CliRun run = run_tdf("tactile convert " + sample + " -o " + out + " --size 120");
    ASSERT_EQ(run.status, 0) << run.output;
    std::size_t warnings = 0;
    for (std::size_t at = run.output.find("physical size unknown"); at != std::string::npos;
         at = run.output.find("physical size unknown", at + 1))
        ++warnings;
    EXPECT_EQ(warnings, 1u) << run.output;
    ImageMetadata metadata;
    read_image(out, metadata);
    EXPECT_EQ(metadata.at("tdf:mm_per_pixel"), "unknown");
    run = run_tdf("tactile convert " + sample + " -o " + out + " --size 120 --size-mm 20 -q");
    ASSERT_EQ(run.status, 0) << run.output;
    read_image(out, metadata);
    EXPECT_EQ(metadata.at("tdf:mm_per_pixel"), fmt::format("{}", 20.0f / 240.0f));
}

TEST(TactileCli, BadInputFailsWithOneLineNamingTheFile) {
    TDF_REQUIRE_TDF_BINARY();
    const std::string missing = test::scratch_dir() + "/no_such_capture.npz";
    const CliRun run = run_tdf("tactile height " + missing + " -o " + test::scratch_dir() + "/x.exr");
    EXPECT_EQ(run.status, 1);
    EXPECT_EQ(run.output.rfind("tdf tactile: ", 0), 0u) << run.output;
    EXPECT_NE(run.output.find(missing), std::string::npos) << run.output;
}

TEST(TactileCli, OptimizeIterationsFollowTheWindowSides) {
    // The default iteration counts (8 4 4) follow fewer window sides; counts given explicitly
    // must fit them.
    TDF_REQUIRE_TDF_BINARY();
    TDF_REQUIRE_SHARED_DATA("tactile/texture_samples/Potato_00000.png");
    const std::string sample = test::shared_data_dir() + "/tactile/texture_samples/Potato_00000.png";
    const std::string out = test::scratch_dir() + "/potato_optimized.png";
    const std::string convert =
        "tactile convert " + sample + " -o " + out + " --size 80 --size-mm 20.4 --synthesis optimize -q";
    CliRun run = run_tdf(convert + " --optimize-windows 16 8");
    EXPECT_EQ(run.status, 0) << run.output;
    run = run_tdf(convert + " --optimize-windows 16 8 --optimize-iterations 3");
    EXPECT_EQ(run.status, 0) << run.output;
    run = run_tdf(convert + " --optimize-windows 16 8 --optimize-iterations 8 4 4");
    EXPECT_EQ(run.status, 1) << run.output;
    EXPECT_EQ(run.output.rfind("tdf tactile: --optimize-iterations: 3 counts for 2 window sides", 0), 0u) << run.output;
    EXPECT_EQ(run.output.find('\n'), run.output.size() - 1) << "one line: " << run.output;
}

TEST(TactileCli, ReportComparesWithTheInputsOwnTiltAndWarnsOnce) {
    // Issue 28: the report states the input's own tilt, the output's and their ratio; a ratio
    // outside [0.75, 1.35] gets one warning line. A gentle normal map converted as it is keeps
    // its tilt (no warning); made 4x steeper with --strength, the report says so.
    TDF_REQUIRE_TDF_BINARY();
    const std::string dir = test::scratch_dir() + "/cli_report";
    std::filesystem::create_directories(dir);
    const std::string input = dir + "/gentle.png";
    write_png(input, encode_normals(test::gentle_veneer_normals(256)), 8, Quantize::Truncate);
    const std::string convert = "tactile convert " + input + " -o " + dir + "/out.png --size 256 --steps-png " + dir;
    auto count = [](const std::string& text, const std::string& what) {
        std::size_t n = 0;
        for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
        return n;
    };
    CliRun run = run_tdf(convert);
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_EQ(count(run.output, "tilt ratio"), 1u) << run.output;
    EXPECT_EQ(count(run.output, "of the input region's"), 0u) << run.output;
    std::ifstream json(dir + "/8_statistics.json");
    const std::string statistics((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
    const Json parsed = Json::parse(statistics);  // one object: one input
    for (const char* key : {"region_mean_tilt", "out_mean_tilt", "tilt_ratio"})
        EXPECT_TRUE(parsed.contains(key) && parsed[key].is_number()) << key << " in " << statistics;
    EXPECT_EQ(parsed.value("strength", 0.0), 1.0) << statistics;
    EXPECT_EQ(parsed.value("input_slopes_known", false), true) << statistics;

    run = run_tdf(convert + " --strength 4");
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_EQ(count(run.output, "steeper than the input: detail tilt"), 1u) << run.output;
    EXPECT_EQ(count(run.output, "of the input region's"), 1u) << "one warning line for the ratio: " << run.output;
}

// Issue 24: `tdf tactile simulate` writes what the sensor measures; bad input (a folder without
// an asset, a point off the mesh, a pad larger than the part) is one line and exit 1, and
// leaves no output folder behind.
TEST(TactileCli, SimulateWritesTouchesAndRefusesBadInputInOneLine) {
    TDF_REQUIRE_TDF_BINARY();
    const std::string dir = test::scratch_dir() + "/cli_simulate";
    test::write_plate(dir + "/plate", 20.0f, 0.05, 2.0);
    const std::string out = dir + "/touches";
    std::filesystem::remove_all(out);
    CliRun run = run_tdf("tactile simulate " + dir + "/plate --points 2 --pad-pixels 60 -o " + out);
    ASSERT_EQ(run.status, 0) << run.output;
    for (const char* file : {"touch_000_height.exr", "touch_000_height.png", "touch_000_normal.png",
                             "touch_001_gelsight.png", "simulate.json"})
        EXPECT_TRUE(std::filesystem::exists(out + "/" + file)) << file << ": " << run.output;

    std::filesystem::create_directories(dir + "/empty");
    const std::string bad_out = dir + "/bad_touches";
    std::filesystem::remove_all(bad_out);
    for (const std::string& arguments :
         {dir + "/empty --at 0.5,0.5", dir + "/plate --at 1.5,0.5", dir + "/plate --at 0.5,0.5 --pad-pixels 300"}) {
        run = run_tdf("tactile simulate " + arguments + " -o " + bad_out);
        EXPECT_EQ(run.status, 1) << arguments << ": " << run.output;
        EXPECT_EQ(std::count(run.output.begin(), run.output.end(), '\n'), 1) << arguments << ": " << run.output;
        EXPECT_FALSE(std::filesystem::exists(bad_out)) << arguments;
    }
}
