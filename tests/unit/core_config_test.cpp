#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/core/rng.h>

#include <gtest/gtest.h>

using namespace tdf;

TEST(Config, OverridesParseJsonValuesAndPlainStrings) {
    Json config = Json::object();
    apply_override(config, "image.width=256");
    apply_override(config, "mesh=meshes/cow.obj");
    apply_override(config, "views.turntable=true");
    EXPECT_EQ(config["image"]["width"].get<int>(), 256);
    EXPECT_EQ(config["mesh"].get<std::string>(), "meshes/cow.obj");
    EXPECT_TRUE(config["views"]["turntable"].get<bool>());
    EXPECT_THROW(apply_override(config, "no_equals_sign"), Error);
}

TEST(Config, ReaderRejectsUnknownKeysAndWrongTypes) {
    const Json config = parse_json(R"({"width": 64, "hieght": 3})", "test.json");
    ConfigReader reader(config, "test.json");
    EXPECT_EQ(reader.get<int>("width", 1), 64);
    EXPECT_EQ(reader.get<int>("height", 7), 7);
    try {
        reader.check_all_read();
        FAIL() << "unknown key not reported";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'hieght'"), std::string::npos) << e.what();
    }
    const Json bad = parse_json(R"({"width": "wide"})", "bad.json");
    ConfigReader bad_reader(bad, "bad.json");
    EXPECT_THROW(bad_reader.get<int>("width", 1), Error);
}

TEST(Config, InvalidJsonNamesTheSource) {
    try {
        parse_json("{\"a\": }", "scene.json");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("scene.json"), std::string::npos);
    }
}

TEST(Rng, SameSeedSameSequenceAndStreamsDiffer) {
    Rng a(42), b(42), c = Rng::stream(42, 1);
    for (int i = 0; i < 100; ++i) {
        const auto va = a.next_u32();
        EXPECT_EQ(va, b.next_u32());
    }
    Rng d(42);
    int equal = 0;
    for (int i = 0; i < 100; ++i) equal += d.next_u32() == c.next_u32();
    EXPECT_LT(equal, 3);
    Rng e(7);
    for (int i = 0; i < 1000; ++i) {
        const int v = e.uniform_int(-30, 30);
        EXPECT_GE(v, -30);
        EXPECT_LT(v, 30);
        const float u = e.uniform();
        EXPECT_GE(u, 0.0f);
        EXPECT_LT(u, 1.0f);
    }
}
