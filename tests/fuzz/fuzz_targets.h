#pragma once
// The bodies of the libFuzzer harnesses (tests/fuzz/fuzz_main.cpp) as plain functions, so that
// the ordinary test suite (tdf_fuzz_regression_tests) replays the regression corpus through
// exactly the same code without libFuzzer.
//
// Each target feeds one input to one reader. The contract checked is the README's: a reader
// either returns or throws tdf::Error; anything else (a crash, a sanitizer report, a leak, any
// other exception such as std::bad_alloc or a nlohmann::json exception) is a bug.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tdf::fuzz {

using TargetFunction = void (*)(const std::uint8_t* data, std::size_t size);

struct Target {
    const char* name;         ///< obj, gltf, ply, image, npy, tmd, scene
    TargetFunction function;  ///< returns normally or throws tdf::Error
};

/// Every target, in a fixed order.
const std::vector<Target>& targets();

/// The target called `name`, or nullptr.
const Target* find_target(const std::string& name);

/// Runs `target` on one input: tdf::Error is swallowed (the expected outcome for bad input),
/// anything else propagates.
void run_one(const Target& target, const std::uint8_t* data, std::size_t size);

/// Separator between the parts of a multi-file input (OBJ + MTL, glTF + .bin, scene + overrides).
inline constexpr const char* kPartSeparator = "\n----\n";

}  // namespace tdf::fuzz
