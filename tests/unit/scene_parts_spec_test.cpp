// The scene file's `parts` section: parsing, defaults, and one clear line per bad input.
#include <tdf/core/error.h>
#include <tdf/scene/scene_file.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <filesystem>

using namespace tdf;

namespace {

Json two_parts() {
    return Json::parse(R"({
      "mesh": "m.obj",
      "parts": {
        "source": {"kind": "colour", "k": 2, "smoothing": 2},
        "list": [
          {"name": "cap", "tactile": {"images": ["ribs.png"]}, "prompt": "a cactus", "select": [0],
           "layout": {"mode": "atlas", "repeat": 4}, "guidance": {"strength": 0.5}},
          {"name": "base", "tactile": {"images": "pebbles.png"},
           "layout": {"mode": "physical", "mm_per_unit": 100}}
        ]
      }
    })");
}

std::string error_of(const Json& j) {
    try {
        parse_scene(j, test::scratch_dir() + "/parts_scene.json");
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace

TEST(ScenePartsSpec, ParsesPartsAndSource) {
    const SceneDescription s = parse_scene(two_parts(), test::scratch_dir() + "/parts_scene.json");
    ASSERT_TRUE(s.parts.enabled());
    EXPECT_EQ(s.parts.source.kind, "colour");
    EXPECT_EQ(s.parts.source.k, 2);
    EXPECT_EQ(s.parts.source.smoothing, 2);
    ASSERT_EQ(s.parts.parts.size(), 2u);
    const PartSpec& cap = s.parts.parts[0];
    EXPECT_EQ(cap.name, "cap");
    EXPECT_EQ(cap.select, std::vector<std::string>{"0"});
    EXPECT_FLOAT_EQ(cap.layout.repeat, 4.f);
    EXPECT_EQ(cap.prompt, "a cactus");
    EXPECT_EQ(cap.guidance["strength"], 0.5);
    EXPECT_EQ(std::filesystem::path(cap.tactile_images[0]).filename(), "ribs.png");
    EXPECT_TRUE(std::filesystem::path(cap.tactile_images[0]).is_absolute());
    EXPECT_EQ(s.parts.parts[1].layout.mode, "physical");
    EXPECT_TRUE(s.parts.parts[1].select.empty());
    // Round trip through the resolved JSON.
    const SceneDescription again = parse_scene(s.to_json(), test::scratch_dir() + "/parts_scene.json");
    EXPECT_EQ(again.parts.parts[1].name, "base");
    EXPECT_EQ(again.parts.source.k, 2);
    // No parts section: disabled.
    EXPECT_FALSE(parse_scene(Json{{"mesh", "m.obj"}}, "x.json").parts.enabled());
}

TEST(ScenePartsSpec, BadInputIsOneLineNamingTheKey) {
    const auto expect = [](Json j, const std::string& needle) {
        const std::string msg = error_of(j);
        EXPECT_NE(msg.find(needle), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    };
    Json none = two_parts();
    none["parts"]["list"] = Json::array();
    expect(none, "'list' is empty; at least 1 part is needed");
    Json no_map = two_parts();
    no_map["parts"]["list"][1]["tactile"]["images"] = Json::array();
    expect(no_map, "parts.list[1]: 'tactile.images' is empty");
    Json same = two_parts();
    same["parts"]["list"][1]["name"] = "cap";
    expect(same, "used by two parts");
    Json bad_name = two_parts();
    bad_name["parts"]["list"][0]["name"] = "a b";
    expect(bad_name, "'name' is 'a b'");
    Json kind = two_parts();
    kind["parts"]["source"]["kind"] = "diffseg";
    expect(kind, "'kind' is 'diffseg'");
    Json k1 = two_parts();
    k1["parts"]["source"]["k"] = 1;
    expect(k1, "parts.source: 'k' must be 0 (choose) or in [2, 16]");
    Json image = two_parts();
    image["parts"]["source"] = {{"kind", "label_image"}};
    expect(image, "'image' is not set");
    Json physical = two_parts();
    physical["parts"]["list"][1]["layout"].erase("mm_per_unit");
    expect(physical, "mm_per_unit");
    Json twice = two_parts();
    twice["parts"]["list"][1]["select"] = {0};
    expect(twice, "'0' is selected by both 'cap' and 'base'");
    Json typo = two_parts();
    typo["parts"]["list"][0]["promt"] = "x";
    expect(typo, "promt");
    Json k3 = two_parts();
    k3["parts"]["list"][0].erase("select");
    k3["parts"]["source"]["k"] = 3;
    expect(k3, "'k' is 3 but there are 2 parts");
    Json list = two_parts();
    list["parts"] = Json::array();
    expect(list, "'parts' must be an object");
    Json external = two_parts();
    external["parts"]["source"] = {{"kind", "external"}};
    expect(external, "'external.command' is not set");
}
