// End-to-end tests of the "external" backend with tdf_test_refiner, a protocol test program that
// applies a known transform (visual: 1 - colour; tactile: (-x, -y, z)) or fails on purpose.
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/guidance/external_backend.h>
#include <tdf/guidance/schedule.h>
#include <tdf/guidance/subprocess.h>
#include <tdf/io/image_io.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>

namespace tdf {
namespace {

namespace fs = std::filesystem;

std::string work_folder(const std::string& name) {
    const std::string folder = test::scratch_dir() + "/guidance_external/" + name;
    fs::remove_all(folder);
    return folder;
}

Json config_for(const std::string& name, std::vector<std::string> extra_args = {}) {
    Json command = Json::array({TDF_TEST_REFINER});
    for (const auto& a : extra_args) command.push_back(a);
    return Json{{"command", command}, {"work_folder", work_folder(name)}, {"timeout_seconds", 60}};
}

GuidanceRequest visual_request(int width = 12, int height = 10) {
    GuidanceRequest r;
    r.kind = GuidanceKind::Visual;
    r.prompt = "an avocado with avocado skin's texture";
    r.strength = 0.504;
    r.iteration = 150;
    r.seed = 7;
    for (int k = 0; k < 2; ++k) {
        Image colour(width, height, 3), normals(width, height, 3), mask(width, height, 1, 1.0f);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                for (int c = 0; c < 3; ++c)
                    colour.at(x, y, c) = float((x * 7 + y * 3 + c * 5 + k * 11) % 16) / 15.0f;
                normals.at(x, y, 2) = 1.0f;
            }
        mask.at(0, 0, 0) = 0.0f;  // one background pixel
        r.images.push_back(colour);
        r.control.push_back(to_bae_control(normals));
        r.masks.push_back(mask);
    }
    return r;
}

GuidanceRequest tactile_request() {
    GuidanceRequest r;
    r.kind = GuidanceKind::Tactile;
    r.prompt = "sks normal map";
    r.strength = 0.8;
    r.iteration = 151;
    Image normals(9, 9, 3), mask(9, 9, 1, 1.0f);
    for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 9; ++x) {
            const float nx = 0.05f * float(x - 4), ny = 0.04f * float(y - 4);
            const float nz = std::sqrt(1.0f - nx * nx - ny * ny);
            normals.at(x, y, 0) = nx, normals.at(x, y, 1) = ny, normals.at(x, y, 2) = nz;
        }
    r.images = {normals};
    r.masks = {mask};
    return r;
}

std::string error_of(GuidanceBackend& backend, const GuidanceRequest& request) {
    try {
        backend.refine(request);
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

TEST(GuidanceExternal, VisualRoundTripAppliesTheProgramsTransform) {
    auto backend = GuidanceBackend::create("external", config_for("visual"));
    const GuidanceRequest request = visual_request();
    const GuidanceResult result = backend->refine(request);
    ASSERT_EQ(result.refined.size(), 2u);
    double max_error = 0.0;
    for (std::size_t k = 0; k < 2; ++k)
        for (int y = 0; y < 10; ++y)
            for (int x = 0; x < 12; ++x)
                for (int c = 0; c < 3; ++c) {
                    // Background (mask exactly 0) is forced to white; elsewhere 1 - input, 8-bit.
                    const float expected = x == 0 && y == 0 ? 1.0f : 1.0f - request.images[k].at(x, y, c);
                    max_error =
                        std::max(max_error, double(std::abs(result.refined[k].at(x, y, c) - expected)));
                }
    EXPECT_LE(max_error, 0.5 / 255.0 + 1e-6) << "max error " << max_error;
    // The call folder is removed after success unless keep_files is set.
    auto* external = dynamic_cast<ExternalBackend*>(backend.get());
    ASSERT_NE(external, nullptr);
    EXPECT_FALSE(fs::exists(external->last_call_folder()));
}

TEST(GuidanceExternal, DefaultWorkFolderIsTemporary) {
    auto backend = std::make_unique<ExternalBackend>(
        ExternalBackend::Options::from_json(Json{{"command", Json::array({TDF_TEST_REFINER})}}));
    backend->refine(visual_request());
    const fs::path work = fs::path(backend->last_call_folder()).parent_path();
    EXPECT_EQ(work.parent_path(), fs::temp_directory_path().lexically_normal());
    EXPECT_TRUE(fs::exists(work));
    backend.reset();
    EXPECT_FALSE(fs::exists(work));
}

TEST(GuidanceExternal, RequestJsonDescribesTheCall) {
    Json config = config_for("request_json");
    config["keep_files"] = true;
    ExternalBackend backend(ExternalBackend::Options::from_json(config));
    backend.refine(visual_request());
    const std::string folder = backend.last_call_folder();
    EXPECT_EQ(fs::path(folder).filename().string(), "visual_00150_0000");
    const Json request = load_json_file(folder + "/request.json");
    EXPECT_EQ(request["protocol"], "tdf-guidance/1");
    EXPECT_EQ(request["kind"], "visual");
    EXPECT_EQ(request["prompt"], "an avocado with avocado skin's texture");
    EXPECT_EQ(request["start_timestep"], 481);
    EXPECT_EQ(request["start_index"], 25);
    EXPECT_DOUBLE_EQ(request["denoise_fraction"].get<double>(), 0.5);
    EXPECT_EQ(request["seed"], 7);
    EXPECT_EQ(request["width"], 12);
    EXPECT_EQ(request["height"], 10);
    ASSERT_EQ(request["images"].size(), 2u);
    EXPECT_EQ(request["images"][1]["control"], "control_1.png");
    EXPECT_TRUE(fs::exists(folder + "/control_1.png"));
    EXPECT_TRUE(fs::exists(folder + "/refined_1.png"));
    EXPECT_NE(read_text_file(folder + "/stdout.txt").find("wrote 2 visual"), std::string::npos);

    // At i = 154 the schedule crosses a DDIM step (spec 5.4): start 461, not 481.
    GuidanceRequest later = visual_request();
    later.iteration = 154;
    later.strength = visual_guidance_strength(154);
    backend.refine(later);
    const Json json154 = load_json_file(backend.last_call_folder() + "/request.json");
    EXPECT_EQ(json154["start_timestep"], 461);
    EXPECT_EQ(json154["strength"].get<double>(), later.strength);
}

TEST(GuidanceExternal, TactileRoundTripThroughExrAndPng) {
    const GuidanceRequest request = tactile_request();
    for (const char* format : {"exr", "png"}) {
        auto backend = GuidanceBackend::create(
            "external", config_for(std::string("tactile_") + format, {"--format", format}));
        const GuidanceResult result = backend->refine(request);
        ASSERT_EQ(result.refined.size(), 1u);
        double max_error = 0.0;
        for (int y = 0; y < 9; ++y)
            for (int x = 0; x < 9; ++x) {
                const float* in = request.images[0].pixel(x, y);
                const float* out = result.refined[0].pixel(x, y);
                max_error = std::max({max_error,
                                      double(std::abs(out[0] + in[0])),
                                      double(std::abs(out[1] + in[1])),
                                      double(std::abs(out[2] - in[2]))});
            }
        // EXR is exact; the 16-bit PNG output is quantised (the input PNG is not used by the program).
        EXPECT_LE(max_error, std::string(format) == "exr" ? 1e-6 : 2.0 / 65535.0) << format;
    }
}

TEST(GuidanceExternal, PlaceholdersAndShellForm) {
    Json config{{"command", std::string(TDF_TEST_REFINER) + " {folder}/request.json"},
                {"work_folder", work_folder("placeholder")}};
    EXPECT_NO_THROW(GuidanceBackend::create("external", config)->refine(visual_request()));
    Json shell{{"command", std::string("cd {folder} && ") + TDF_TEST_REFINER + " request.json 2>&1 | cat"},
               {"shell", true},
               {"work_folder", work_folder("shell")}};
    EXPECT_NO_THROW(GuidanceBackend::create("external", shell)->refine(visual_request()));
}

TEST(GuidanceExternal, NonZeroExitNamesCommandAndStderr) {
    auto backend = GuidanceBackend::create("external", config_for("exit", {"--exit", "3"}));
    const std::string message = error_of(*backend, visual_request());
    EXPECT_NE(message.find("tdf_test_refiner"), std::string::npos) << message;
    EXPECT_NE(message.find("status 3"), std::string::npos) << message;
    EXPECT_NE(message.find("failing on purpose"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
    // The call folder is kept for inspection.
    EXPECT_TRUE(fs::exists(dynamic_cast<ExternalBackend&>(*backend).last_call_folder() + "/request.json"));
}

TEST(GuidanceExternal, TimeoutKillsTheProgram) {
    Json config = config_for("timeout", {"--hang"});
    config["timeout_seconds"] = 0.3;
    auto backend = GuidanceBackend::create("external", config);
    const std::string message = error_of(*backend, visual_request());
    EXPECT_NE(message.find("timed out after 0.3 s"), std::string::npos) << message;
    EXPECT_NE(message.find("tdf_test_refiner"), std::string::npos) << message;
}

TEST(GuidanceExternal, MissingWrongSizeAndGrayOutputsAreErrors) {
    auto missing = GuidanceBackend::create("external", config_for("missing", {"--skip-output", "1"}));
    std::string message = error_of(*missing, visual_request());
    EXPECT_NE(message.find("did not write"), std::string::npos) << message;
    EXPECT_NE(message.find("refined_1.png"), std::string::npos) << message;

    auto wrong = GuidanceBackend::create("external", config_for("wrong_size", {"--wrong-size"}));
    message = error_of(*wrong, visual_request());
    EXPECT_NE(message.find("of size 13x10, expected 12x10"), std::string::npos) << message;
    EXPECT_NE(message.find("refined_0.png"), std::string::npos) << message;

    auto gray = GuidanceBackend::create("external", config_for("gray", {"--gray"}));
    message = error_of(*gray, visual_request());
    EXPECT_NE(message.find("1 channel(s), expected RGB"), std::string::npos) << message;
}

TEST(GuidanceExternal, UnknownProgramAndUnsupportedKind) {
    Json config{{"command", Json::array({"tdf-no-such-program-xyz"})},
                {"work_folder", work_folder("nosuch")}};
    auto backend = GuidanceBackend::create("external", config);
    const std::string message = error_of(*backend, visual_request());
    EXPECT_NE(message.find("cannot run 'tdf-no-such-program-xyz'"), std::string::npos) << message;

    Json visual_only = config_for("visual_only");
    visual_only["kinds"] = Json::array({"visual"});
    auto restricted = GuidanceBackend::create("external", visual_only);
    EXPECT_FALSE(restricted->supports(GuidanceKind::Tactile));
    EXPECT_NE(error_of(*restricted, tactile_request()).find("not configured for tactile"), std::string::npos);
}

TEST(GuidanceExternal, ConfigErrors) {
    EXPECT_THROW(ExternalBackend::Options::from_json(Json{{"command", 3}}), Error);
    EXPECT_THROW(ExternalBackend::Options::from_json(Json{{"command", ""}}), Error);
    EXPECT_THROW(ExternalBackend::Options::from_json(Json{{"command", "sd"}, {"timeout_seconds", 0}}), Error);
    EXPECT_THROW(ExternalBackend::Options::from_json(Json{{"command", Json::array({"sd"})}, {"shell", true}}),
                 Error);
    EXPECT_THROW(
        ExternalBackend::Options::from_json(Json{{"command", "sd"}, {"kinds", Json::array({"audio"})}}),
        Error);
    EXPECT_THROW(ExternalBackend::Options::from_json(Json{{"command", "sd"}, {"timeout", 5}}), Error);
    const auto o = ExternalBackend::Options::from_json(Json{{"command", "sd  -M img2img --strength 0.5"}});
    EXPECT_EQ(o.command, (std::vector<std::string>{"sd", "-M", "img2img", "--strength", "0.5"}));
}

TEST(GuidanceSubprocess, ReportsExitCodesAndTails) {
    const std::string folder = work_folder("subprocess");
    fs::create_directories(folder);
    const ProcessOutcome ok = run_process({"/bin/sh", "-c", "echo one; echo two >&2; echo three >&2; exit 4"},
                                          folder,
                                          30.0,
                                          folder + "/out.txt",
                                          folder + "/err.txt");
    EXPECT_FALSE(ok.timed_out);
    EXPECT_EQ(ok.exit_code, 4);
    EXPECT_EQ(file_tail(folder + "/err.txt", 1), "three");
    EXPECT_EQ(file_tail(folder + "/err.txt", 5), "two\nthree");
    EXPECT_EQ(format_command({"sd", "--prompt", "a b"}), "sd --prompt 'a b'");
}

}  // namespace
}  // namespace tdf
