#pragma once
/// Content hashes for change detection (checkpoints, resume checks, completion records). Not
/// cryptographic: FNV-1a, 64 bits, printed as 16 lower-case hex digits.
#include <cstddef>
#include <cstdint>
#include <string>

namespace tdf {

constexpr std::uint64_t kFnv1aSeed = 1469598103934665603ULL;

/// FNV-1a over `size` bytes, continuing from `hash` (start with kFnv1aSeed).
std::uint64_t fnv1a(const char* data, std::size_t size, std::uint64_t hash = kFnv1aSeed);

/// fnv1a() over `size` zero bytes, in O(log size) multiplications.
std::uint64_t fnv1a_zeros(std::size_t size, std::uint64_t hash = kFnv1aSeed);

/// FNV-1a of a whole file, read in blocks; throws tdf::Error naming the file when unreadable.
std::uint64_t hash_file(const std::string& path);

/// 16 lower-case hex digits.
std::string hash_hex(std::uint64_t hash);

}  // namespace tdf
