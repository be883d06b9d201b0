#pragma once
// Where tests find their inputs. Real data lives in ../shared/data (never copied into the
// repository); tests that need it call TDF_REQUIRE_SHARED_DATA and are skipped with a clear
// message when it is absent.
#include <gtest/gtest.h>

#include <string>

namespace tdf::test {

/// The repository root.
std::string source_dir();
/// A writable scratch folder for this test binary (under the build tree).
std::string scratch_dir();
/// `../shared/data` next to the repository, or $TDF_SHARED_DATA; empty when absent.
std::string shared_data_dir();

}  // namespace tdf::test

#define TDF_REQUIRE_SHARED_DATA(relative)                                                       \
    do {                                                                                        \
        if (::tdf::test::shared_data_dir().empty())                                             \
            GTEST_SKIP() << "shared data not found (expected ../shared/data next to the "      \
                            "repository or $TDF_SHARED_DATA); skipping";                        \
        if (!std::filesystem::exists(::tdf::test::shared_data_dir() + "/" + (relative)))       \
            GTEST_SKIP() << "shared data file missing: " << (relative) << "; skipping";         \
    } while (0)
