// release(): the storage is given back (a vector assigned `{}` keeps its capacity in libstdc++,
// which is how several "released" buffers stayed allocated until this helper).
#include <tdf/core/release.h>
#include <tdf/core/vec.h>

#include <gtest/gtest.h>

namespace tdf {
namespace {

TEST(Release, FreesTheStorageOfEveryVectorGiven) {
    std::vector<float> a(1000, 1.0f);
    std::vector<Vec3f> b(500), c(20);
    release(a);
    EXPECT_TRUE(a.empty());
    EXPECT_EQ(a.capacity(), 0u);
    release(b, c);
    EXPECT_EQ(b.capacity(), 0u);
    EXPECT_EQ(c.capacity(), 0u);
    a.assign(10, 2.0f);  // still usable
    EXPECT_EQ(a[9], 2.0f);
}

}  // namespace
}  // namespace tdf
