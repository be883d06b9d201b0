#include <fmt/format.h>
#include <tdf/core/error.h>
#include <tdf/core/hash.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <vector>

namespace tdf {

namespace {
constexpr std::uint64_t kFnv1aPrime = 1099511628211ULL;
}  // namespace

std::uint64_t fnv1a(const char* data, std::size_t size, std::uint64_t hash) {
    for (std::size_t i = 0; i < size; ++i) {
        hash ^= std::uint8_t(data[i]);
        hash *= kFnv1aPrime;
    }
    return hash;
}

std::uint64_t fnv1a_zeros(std::size_t size, std::uint64_t hash) {
    // A zero byte leaves the xor unchanged, so `size` of them multiply by prime^size (mod 2^64):
    // square-and-multiply instead of one multiplication a byte.
    std::uint64_t power = kFnv1aPrime;
    for (std::size_t n = size; n > 0; n >>= 1) {
        if (n & 1) hash *= power;
        power *= power;
    }
    return hash;
}

std::uint64_t hash_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw_error("cannot open '{}': {}", path, std::strerror(errno));
    std::vector<char> block(1 << 20);
    std::uint64_t hash = kFnv1aSeed;
    while (in) {
        in.read(block.data(), std::streamsize(block.size()));
        hash = fnv1a(block.data(), std::size_t(in.gcount()), hash);
    }
    if (in.bad()) throw_error("cannot read '{}': {}", path, std::strerror(errno));
    return hash;
}

std::string hash_hex(std::uint64_t hash) { return fmt::format("{:016x}", hash); }

}  // namespace tdf
