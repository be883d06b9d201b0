#include <tdf/core/error.h>
#include <tdf/guidance/schedule.h>

#include <gtest/gtest.h>

#include <map>

namespace tdf {
namespace {

TEST(GuidanceSchedule, StepRatioMatchesReference) {
    // step = i + 1; (step - 150) / 50, capped at 1 (spec 5.1).
    EXPECT_DOUBLE_EQ(step_ratio(150, 150, 200), 0.02);
    EXPECT_DOUBLE_EQ(step_ratio(174, 150, 200), 0.5);
    EXPECT_DOUBLE_EQ(step_ratio(199, 150, 200), 1.0);
    EXPECT_DOUBLE_EQ(step_ratio(260, 150, 200), 1.0);
    EXPECT_LT(step_ratio(10, 150, 200), 0.0);
}

TEST(GuidanceSchedule, PhasesStartAt150And151) {
    EXPECT_FALSE(visual_guidance_active(149));
    EXPECT_TRUE(visual_guidance_active(150));
    EXPECT_FALSE(tactile_guidance_active(150));
    EXPECT_TRUE(tactile_guidance_active(151));
}

TEST(GuidanceSchedule, VisualStrengthRunsFromHalfToSevenTenths) {
    EXPECT_NEAR(visual_guidance_strength(150), 0.504, 1e-12);
    EXPECT_NEAR(visual_guidance_strength(199), 0.7, 1e-12);
    for (int i = 151; i < 200; ++i) EXPECT_GT(visual_guidance_strength(i), visual_guidance_strength(i - 1));
}

TEST(GuidanceSchedule, DdimTimestepsAreLeadingWithOffsetOne) {
    const std::vector<int> t = ddim_timesteps(50);
    ASSERT_EQ(t.size(), 50u);
    EXPECT_EQ(t.front(), 981);
    EXPECT_EQ(t[1], 961);
    EXPECT_EQ(t.back(), 1);
}

TEST(GuidanceSchedule, VisualStartTimestepTableMatchesSpec) {
    // Spec 5.4: counts of the start timestep over the 50 refinement iterations i = 150..199.
    const std::map<int, int> expected = {{481, 4},
                                         {461, 5},
                                         {441, 6},
                                         {421, 5},
                                         {401, 4},
                                         {381, 5},
                                         {361, 6},
                                         {341, 5},
                                         {321, 4},
                                         {301, 5},
                                         {281, 1}};
    std::map<int, int> counts;
    for (int i = 150; i < 200; ++i) ++counts[ddim_start_timestep(visual_guidance_strength(i))];
    EXPECT_EQ(counts, expected);
    // The floating-point boundaries named in the spec: i = 150..153 -> 481, i = 154 -> 461,
    // only i = 199 reaches 281.
    EXPECT_EQ(ddim_start_timestep(visual_guidance_strength(153)), 481);
    EXPECT_EQ(ddim_start_timestep(visual_guidance_strength(154)), 461);
    EXPECT_EQ(ddim_start_timestep(visual_guidance_strength(198)), 301);
    EXPECT_EQ(ddim_start_timestep(visual_guidance_strength(199)), 281);
}

TEST(GuidanceSchedule, TactileStrengthStartsAt181WithTenSteps) {
    EXPECT_EQ(ddim_start_index(kTactileGuidanceStrength), 40);
    EXPECT_EQ(ddim_start_timestep(kTactileGuidanceStrength), 181);
    EXPECT_NEAR(denoise_fraction(kTactileGuidanceStrength), 0.2, 1e-12);
}

TEST(GuidanceSchedule, DenoiseFractionIsTheImg2ImgStrength) {
    EXPECT_NEAR(denoise_fraction(visual_guidance_strength(150)), 0.5, 1e-12);
    EXPECT_NEAR(denoise_fraction(visual_guidance_strength(199)), 0.3, 1e-12);
    EXPECT_EQ(ddim_start_index(1.0), 49);  // clamped, the reference would index past the end
    EXPECT_THROW(ddim_start_index(1.5), Error);
}

TEST(GuidancePrompt, TextureDescriptionsMatchTheReferenceTable) {
    EXPECT_EQ(texture_descriptions().size(), 28u);
    EXPECT_EQ(texture_description("avocado"), "avocado skin's");
    EXPECT_EQ(texture_description("GreenSweater"), "crochet");
    EXPECT_EQ(texture_description("OrangeGlove"), "heat resistant rubber with heart-shape pattern");
    EXPECT_EQ(texture_description("BlackBase"), "flat");
    try {
        texture_description("Velvet");
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("Velvet"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("GreenSweater"), std::string::npos);
    }
}

TEST(GuidancePrompt, ObjectWordsDropDigitsAndGeneratorNames) {
    EXPECT_EQ(object_words("an_avocado_2"), "an avocado");
    EXPECT_EQ(object_words("a_beanie_1"), "a beanie");
    EXPECT_EQ(object_words("a_coffee_cup_RichDreamer"), "a coffee cup");
    EXPECT_EQ(object_words("InstantMesh_a_potato_12"), "a potato");
    EXPECT_EQ(object_words("lamp1"), "lamp1");  // digits inside a word stay
}

TEST(GuidancePrompt, SingleTexturePromptMatchesSpecExample) {
    EXPECT_EQ(textured_prompt("an_avocado_2", "avocado"),
              "an avocado with avocado skin's texture, highly detailed, hd, best quality, front lighting");
    EXPECT_EQ(std::string(kNegativePrompt),
              "bad quality, blurred, low resolution, low quality, worst quality, low res, glitch, deformed, "
              "mutated, ugly, disfigured");
}

TEST(GuidancePrompt, MultiPartPromptHasPartsAndTokenIndices) {
    const MultiPartPrompt p = multi_part_prompt("a_cactus_in_a_pot_3", "Orange", "OrangeGlove");
    EXPECT_EQ(
        p.prompt,
        "a cactus in a pot, cactus with orange texture, pot with heat resistant rubber with heart-shape "
        "pattern texture, highly detailed, hd, best quality, front lighting");
    EXPECT_EQ(p.part_a_token, 2);
    EXPECT_EQ(p.part_b_token, 5);
    EXPECT_THROW(multi_part_prompt("a_teapot", "Orange", "Corn"), Error);
}

}  // namespace
}  // namespace tdf
