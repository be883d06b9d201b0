#include <tdf/core/error.h>

#include <cstdio>
#include <cstdlib>

namespace tdf {

void check_failed(const char* file, int line, const std::string& what) {
    std::fprintf(stderr, "tdf: internal check failed at %s:%d: %s\n", file, line, what.c_str());
    std::abort();
}

}  // namespace tdf
