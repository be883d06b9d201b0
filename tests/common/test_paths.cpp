#include "common/test_paths.h"

#include <cstdlib>
#include <filesystem>

namespace tdf::test {

std::string source_dir() { return TDF_SOURCE_DIR; }

std::string scratch_dir() {
    const std::string dir = std::string(TDF_BINARY_DIR) + "/test-scratch";
    std::filesystem::create_directories(dir);
    return dir;
}

std::string shared_data_dir() {
    if (const char* env = std::getenv("TDF_SHARED_DATA"))
        if (std::filesystem::is_directory(env)) return env;
    const auto candidate = std::filesystem::path(TDF_SOURCE_DIR).parent_path() / "shared" / "data";
    if (std::filesystem::is_directory(candidate)) return candidate.string();
    return {};
}

}  // namespace tdf::test
