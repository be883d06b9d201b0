// One libFuzzer harness; TDF_FUZZ_TARGET names the reader (tests/fuzz/fuzz_targets.cpp).
// Built by -DTDF_FUZZ=ON with clang; run with scripts/fuzz.sh.
#include <tdf/core/log.h>

#include <cstdio>
#include <cstdlib>

#include "fuzz/fuzz_targets.h"

namespace {
const tdf::fuzz::Target* g_target = nullptr;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    tdf::set_log_level(tdf::LogLevel::Quiet);
    g_target = tdf::fuzz::find_target(TDF_FUZZ_TARGET);
    if (!g_target) {
        std::fprintf(stderr, "unknown fuzz target %s\n", TDF_FUZZ_TARGET);
        std::abort();
    }
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    tdf::fuzz::run_one(*g_target, data, size);
    return 0;
}
