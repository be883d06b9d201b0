#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/tactile/tmd_reader.h>

#include <filesystem>
#include <fstream>

#include "common/test_paths.h"

using namespace tdf;

namespace {
const std::string kGroove = "tactile/gelsight_groove_scan/heightmap.tmd";
}

TEST(TmdReader, ReadsTheGrooveScanWithItsLengths) {
    TDF_REQUIRE_SHARED_DATA(kGroove);
    const TmdFile tmd = read_tmd(test::shared_data_dir() + "/" + kGroove);
    EXPECT_EQ(tmd.map.height.width(), 616);
    EXPECT_EQ(tmd.map.height.height(), 514);
    EXPECT_NEAR(tmd.length_x_mm, 16.914f, 1e-3f);
    EXPECT_NEAR(tmd.length_y_mm, 14.113f, 1e-3f);
    // scan.yaml beside the file: 0.027458113509339 mm per pixel.
    EXPECT_NEAR(tmd.map.mm_per_pixel, 0.0274581f, 1e-6f);
    EXPECT_TRUE(tmd.map.height.all_finite());
    const auto [lo, hi] = std::minmax_element(tmd.map.height.values().begin(), tmd.map.height.values().end());
    EXPECT_GT(*hi - *lo, 0.1f);  // machined grooves, tenths of a millimetre deep
    EXPECT_LT(*hi - *lo, 2.0f);
}

TEST(TmdReader, RejectsTruncatedAndForeignFiles) {
    TDF_REQUIRE_SHARED_DATA(kGroove);
    const std::string bytes = read_text_file(test::shared_data_dir() + "/" + kGroove);
    const std::string truncated = test::scratch_dir() + "/truncated.tmd";
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() - 100);
    try {
        read_tmd(truncated);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(truncated), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos);
    }
    const std::string foreign = test::scratch_dir() + "/foreign.tmd";
    std::ofstream(foreign, std::ios::binary) << "Binary TrueMap Data File v1.0\r\n";
    EXPECT_THROW(read_tmd(foreign), Error);
}
