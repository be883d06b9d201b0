#include <tdf/core/error.h>
#include <tdf/field/hash_grid.h>

#include <gtest/gtest.h>

#include <vector>

using namespace tdf;

TEST(HashGrid, LevelResolutionsMatchReference) {
    const HashGrid grid(HashGridConfig{});
    // Spec 4.2: res_l = ceil(scale_l) + 1 with float32 scale_l = 2^(l log2 1.5) * 16 - 1.
    const std::uint32_t expected[16] = {16, 24, 36, 54, 81, 122, 183, 274, 411, 616, 923, 1384, 2076, 3114, 4671, 7007};
    ASSERT_EQ(grid.level_count(), 16);
    for (int l = 0; l < 16; ++l) EXPECT_EQ(grid.levels()[std::size_t(l)].resolution, expected[l]) << "level " << l;
    EXPECT_EQ(grid.levels()[0].table_size, 4096u);
    EXPECT_EQ(grid.levels()[1].table_size, 13824u);
    EXPECT_FALSE(grid.levels()[0].hashed);
    EXPECT_FALSE(grid.levels()[1].hashed);
    for (int l = 2; l < 16; ++l) {
        EXPECT_EQ(grid.levels()[std::size_t(l)].table_size, 32768u);
        EXPECT_TRUE(grid.levels()[std::size_t(l)].hashed);
    }
    EXPECT_EQ(grid.entry_count(), 476672u);
    EXPECT_EQ(grid.parameter_count(), 953344u);
    EXPECT_EQ(grid.feature_count(), 32);
}
