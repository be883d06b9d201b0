// Image's storage: filled in parallel when large (the same values on any thread count), its
// allocator's containers keep what they hold when they grow, and large blocks start on a cache
// line.
#include <gtest/gtest.h>
#include <tdf/core/image.h>
#include <tdf/core/parallel.h>

#include <cstdint>

namespace tdf {
namespace {

TEST(Image, EveryValueTakesTheFillOnAnyThreadCount) {
    // 301 x 257 x 3 values: several fill chunks, the last one partial; and a one-chunk image.
    for (const int threads : {1, 2}) {
        ThreadLimit limit(threads);
        for (const auto& [w, h] : {std::pair{301, 257}, std::pair{5, 3}}) {
            const Image image(w, h, 3, 0.25f);
            ASSERT_EQ(image.values().size(), std::size_t(w) * std::size_t(h) * 3);
            std::size_t wrong = 0;
            for (float v : image.values()) wrong += v != 0.25f;
            EXPECT_EQ(wrong, 0u) << w << "x" << h << ", " << threads << " threads";
            const Image zero(w, h, 2);
            for (float v : zero.values()) wrong += v != 0.0f;
            EXPECT_EQ(wrong, 0u) << "default fill, " << w << "x" << h;
        }
    }
}

TEST(Image, AnUninitializedImageHasItsShapeAndTakesWrites) {
    Image image(64, 32, 4, Image::Uninitialized{});
    EXPECT_EQ(image.width(), 64);
    EXPECT_EQ(image.height(), 32);
    EXPECT_EQ(image.channels(), 4);
    ASSERT_EQ(image.values().size(), 64u * 32u * 4u);
    parallel_fill(image.data(), image.values().size(), 2.0f);
    EXPECT_EQ(image.at(63, 31, 3), 2.0f);
    EXPECT_TRUE(image.all_finite());
}

TEST(Image, ValuesKeepTheirContentsWhenTheStorageGrows) {
    ImageValues values(3, 1.5f);  // a value given is written
    values.resize(100000);        // reallocates: the first three move with their values
    EXPECT_EQ(values[0], 1.5f);
    EXPECT_EQ(values[2], 1.5f);
    values.assign(10, -1.0f);
    for (float v : values) EXPECT_EQ(v, -1.0f);
}

// Large blocks start on a cache line (the renderer's streaming stores write whole lines only
// there); small ones are plain operator new blocks. Both grow, shrink and free cleanly (the
// sanitized build checks that each block goes back as it came).
TEST(Image, LargeStorageStartsOnACacheLine) {
    using Allocator = ImageValues::allocator_type;
    constexpr std::size_t kLarge = Allocator::kAlignedFrom / sizeof(float);
    for (int round = 0; round < 8; ++round) {
        ImageValues small(16 + std::size_t(round), 2.f);
        ImageValues large(kLarge + std::size_t(round) * 7, 3.f);
        EXPECT_EQ(reinterpret_cast<std::uintptr_t>(large.data()) % Allocator::kAlignment, 0u);
        EXPECT_EQ(large.front(), 3.f);
        EXPECT_EQ(large.back(), 3.f);
        large.resize(large.size() * 3, 4.f);  // reallocates
        EXPECT_EQ(reinterpret_cast<std::uintptr_t>(large.data()) % Allocator::kAlignment, 0u);
        EXPECT_EQ(large[kLarge - 1], 3.f);
        EXPECT_EQ(large.back(), 4.f);
        large.swap(small);
        large.shrink_to_fit();
        EXPECT_EQ(large.size(), 16u + std::size_t(round));
    }
    const Image image(512, 512, 3);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(image.data()) % 64, 0u);
}

}  // namespace
}  // namespace tdf
