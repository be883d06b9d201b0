#include <tdf/core/hash.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace tdf;

// FNV-1a's published 64-bit test vectors, from the published offset basis 14695981039346656037.
// tdf's own seed (kFnv1aSeed) is that number without its last digit, so its hashes are not the
// standard ones; it stays as it is, since checkpoints, resume checks and completion records hold
// hashes made with it.
TEST(Hash, Fnv1aMatchesTheReferenceVectorsFromTheStandardBasis) {
    constexpr std::uint64_t kStandardBasis = 14695981039346656037ULL;
    EXPECT_EQ(fnv1a("", 0, kStandardBasis), 0xcbf29ce484222325ULL);
    EXPECT_EQ(fnv1a("a", 1, kStandardBasis), 0xaf63dc4c8601ec8cULL);
    EXPECT_EQ(fnv1a("foobar", 6, kStandardBasis), 0x85944171f73967e8ULL);
    EXPECT_EQ(kFnv1aSeed, 1469598103934665603ULL);
}

// The closed form for runs of zeros (checkpoints' zero moments) equals hashing the bytes, from
// any starting hash and for lengths around every power of two a checkpoint meets.
TEST(Hash, ZerosInClosedFormEqualHashingTheBytes) {
    const std::vector<char> zeros(1 << 17, 0);
    const std::uint64_t start = fnv1a("tdf", 3);
    for (std::size_t size : {std::size_t(0), std::size_t(1), std::size_t(2), std::size_t(3), std::size_t(7),
                             std::size_t(8), std::size_t(4095), std::size_t(4096), std::size_t(65537),
                             std::size_t(1 << 17)}) {
        EXPECT_EQ(fnv1a_zeros(size, start), fnv1a(zeros.data(), size, start)) << size << " zeros";
        EXPECT_EQ(fnv1a_zeros(size), fnv1a(zeros.data(), size)) << size << " zeros from the seed";
    }
    // A run of zeros in the middle of other bytes.
    const std::string head = "header", tail = "tail";
    std::string all = head + std::string(1000, '\0') + tail;
    const std::uint64_t piecewise = fnv1a(tail.data(), tail.size(), fnv1a_zeros(1000, fnv1a(head.data(), head.size())));
    EXPECT_EQ(piecewise, fnv1a(all.data(), all.size()));
}
