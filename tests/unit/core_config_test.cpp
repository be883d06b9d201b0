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

TEST(Config, DuplicateKeysAreErrorsNamingTheKey) {
    try {
        parse_json(R"({"mesh": "a.obj", "views": {"radius": 2, "radius": 3}})", "dup.json");
        FAIL() << "duplicate key accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("dup.json: duplicate key 'views.radius'"), std::string::npos)
            << e.what();
    }
    // The same key in different objects (and in objects inside arrays) is fine.
    const Json ok = parse_json(R"({"a": {"x": 1}, "b": {"x": 2}, "l": [{"x": 1}, {"x": 2}]})", "ok.json");
    EXPECT_EQ(ok["b"]["x"].get<int>(), 2);
    Json config = Json::object();
    EXPECT_THROW(apply_override(config, R"(views={"count": 1, "count": 2})"), Error);
}

TEST(Config, NumbersOutOfRangeNameTheSourceOrKey) {
    try {
        parse_json(R"({"ssaa": 1e999})", "big.json");
        FAIL() << "1e999 accepted";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_EQ(message.rfind("big.json: invalid JSON: ", 0), 0u) << message;
        EXPECT_EQ(message.find("[json.exception"), std::string::npos) << message;
    }
    Json config = Json::object();
    try {
        apply_override(config, "ssaa=1e999");
        FAIL() << "override 1e999 accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("override 'ssaa=1e999'"), std::string::npos) << e.what();
    }
    // Integers: 2^64 - 1 is a valid unsigned 64-bit value, -1 is not, and nothing wraps.
    const Json values =
        parse_json(R"({"seed": 18446744073709551615, "neg": -1, "big": 4294967808})", "v.json");
    ConfigReader reader(values, "v.json");
    EXPECT_EQ(reader.get<std::uint64_t>("seed", 0), 18446744073709551615ull);
    EXPECT_THROW(reader.get<std::int64_t>("seed", 0), Error);
    try {
        reader.get<std::uint64_t>("neg", 0);
        FAIL() << "-1 read as an unsigned value";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'neg' must be an integer in [0, 18446744073709551615], got -1"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_THROW(reader.get<int>("big", 0), Error);  // would wrap to 512
    EXPECT_EQ(reader.get<std::int64_t>("big", 0), 4294967808ll);
}
