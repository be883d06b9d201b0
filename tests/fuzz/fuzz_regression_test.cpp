// Replays tests/fuzz/regressions/<target>/* (inputs that once crashed a reader or made it
// allocate without bound, found by scripts/fuzz.sh) through the same harness bodies as the
// fuzzers. Each must now return or throw tdf::Error; run_one rethrows anything else.
#include <tdf/core/atomic_file.h>
#include <tdf/core/log.h>

#include <filesystem>
#include <string>

#include "common/test_paths.h"
#include "fuzz/fuzz_targets.h"

namespace fs = std::filesystem;
using namespace std::string_literals;

namespace {

class FuzzRegression : public ::testing::TestWithParam<std::string> {};

TEST_P(FuzzRegression, EveryStoredInputIsHandled) {
    tdf::set_log_level(tdf::LogLevel::Quiet);
    const tdf::fuzz::Target* target = tdf::fuzz::find_target(GetParam());
    ASSERT_NE(target, nullptr);
    const fs::path folder = fs::path(tdf::test::source_dir()) / "tests/fuzz/regressions" / GetParam();
    std::size_t replayed = 0;
    if (fs::is_directory(folder))
        for (const auto& entry : fs::directory_iterator(folder)) {
            if (!entry.is_regular_file()) continue;
            const std::string bytes = tdf::read_text_file(entry.path().string());
            EXPECT_NO_THROW(tdf::fuzz::run_one(
                *target, reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()))
                << entry.path();
            ++replayed;
        }
    RecordProperty("replayed", int(replayed));
}

// Hand-written edge cases every harness must survive (empty input, a lone separator, noise).
TEST_P(FuzzRegression, EdgeCaseInputsAreHandled) {
    tdf::set_log_level(tdf::LogLevel::Quiet);
    const tdf::fuzz::Target* target = tdf::fuzz::find_target(GetParam());
    ASSERT_NE(target, nullptr);
    // The literal's own length (23 bytes with the leading NUL): a hand-counted 28 read past its
    // end (found by the ASan run of the whole suite).
    const std::string noise("\x00\xff\x7f\x80glTF\x93NUMPY PK\x03\x04\x89PNG"s);
    for (const std::string& input : {std::string(),
                                     std::string(tdf::fuzz::kPartSeparator),
                                     noise,
                                     std::string("{}"),
                                     std::string(4096, '\n')})
        EXPECT_NO_THROW(
            tdf::fuzz::run_one(*target, reinterpret_cast<const std::uint8_t*>(input.data()), input.size()));
}

INSTANTIATE_TEST_SUITE_P(Readers, FuzzRegression,
                         ::testing::Values("obj", "gltf", "ply", "image", "npy", "tmd", "scene"));

}  // namespace
