// What the trainer lets go while the asset is written (release_derived, release_training_state,
// release_target_inputs) must give its memory back, not only look empty: `v = {}` kept every
// one of these buffers allocated until tdf::release replaced it (4096^2: 4.6 -> 3.9 GB).
#include <tdf/scene/procedural_mesh.h>
#include <tdf/train/learned_maps.h>
#include <tdf/train/texel_atlas.h>

#include <gtest/gtest.h>

namespace tdf {
namespace {

TEST(ReleasedState, TheAtlasAndTheLearnedMapsGiveTheirMemoryBack) {
    TexelAtlas atlas = TexelAtlas::build(make_quad(), 32);
    ASSERT_GT(atlas.covered_count(), 0u);
    ASSERT_TRUE(atlas.has_target_inputs());
    atlas.release_target_inputs();
    EXPECT_EQ(atlas.uvs.capacity(), 0u);
    EXPECT_EQ(atlas.raster.barycentric.capacity(), 0u);
    EXPECT_FALSE(atlas.has_target_inputs());
    EXPECT_EQ(atlas.points.size(), atlas.covered_count());  // what training still reads stays

    LearnedMaps maps(atlas);
    ASSERT_EQ(maps.field_outputs().size(), atlas.covered_count());
    maps.release_derived();
    EXPECT_EQ(maps.field_outputs().capacity(), 0u);
    EXPECT_EQ(maps.residual().size(), atlas.covered_count() * LearnedMaps::kResidualPerTexel);
    maps.release_training_state();
    EXPECT_EQ(maps.residual().capacity(), 0u);
    EXPECT_EQ(maps.field_outputs().capacity(), 0u);
}

}  // namespace
}  // namespace tdf
