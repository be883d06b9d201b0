// Runs that survive the scheduler (README "Runs that survive"): output names, the folder lock,
// stop signals with a checkpoint and a byte-identical resume, input hashes on resume, stale
// temporaries, and the completion record.
#include <gtest/gtest.h>
#include <signal.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/core/hash.h>
#include <tdf/io/image_io.h>
#include <tdf/optim/checkpoint.h>
#include <tdf/scene/scene_file.h>
#include <tdf/train/optimize_run.h>
#include <tdf/train/run_guard.h>

#include <filesystem>

#include "common/test_paths.h"

using namespace tdf;
namespace fs = std::filesystem;

namespace {

const std::string kSceneFolder = test::source_dir() + "/scenes/pebble_sphere";

// The smallest run in which every stage works: a second or two.
std::vector<std::string> tiny_run(int iterations, int init_iterations) {
    return {"optimize.iterations=" + std::to_string(iterations),
            "optimize.init_iterations=" + std::to_string(init_iterations),
            "optimize.resolution=32",
            "optimize.patch_resolution=32",
            "optimize.batch_size=1",
            "optimize.patch_batch_size=1",
            "optimize.held_out_views=1",
            "optimize.held_out_patches=1",
            "optimize.checkpoint_every=0",
            "export.texture_size=64",
            "export.turntable_views=1",
            "export.turntable_resolution=32",
            "export.glb=false",
            "guidance.tactile=none",
            "guidance.visual=none"};
}

OptimizeOptions options_for(const std::string& folder, std::vector<std::string> overrides,
                            const std::string& scene = kSceneFolder + "/scene.json") {
    OptimizeOptions options;
    options.scene_path = scene;
    options.overrides = std::move(overrides);
    options.output_dir = test::scratch_dir() + "/run_guard/" + folder;
    options.name = "pebble";
    return options;
}

std::string fresh(const std::string& folder) {
    const std::string path = test::scratch_dir() + "/run_guard/" + folder;
    fs::remove_all(path);
    return path;
}

template <typename F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

// Copies the pebble scene into a scratch folder, so a test can change its inputs.
std::string copy_scene(const std::string& folder) {
    const std::string target = fresh(folder);
    fs::create_directories(target);
    for (const auto& entry : fs::directory_iterator(kSceneFolder))
        if (entry.is_regular_file())
            fs::copy_file(entry.path(), target + "/" + entry.path().filename().string());
    return target + "/scene.json";
}

}  // namespace

TEST(RunGuard, EmptyOutputAndEscapingNamesAreRefused) {
    EXPECT_NE(error_of([] { validate_output_target("", "pebble"); }).find("-o/--output is empty"),
              std::string::npos);
    for (const char* name : {"../x", "a/b", "..", ".", ""})
        EXPECT_NE(error_of([&] { validate_output_target("out", name); }).find("--name"), std::string::npos)
            << name;
    EXPECT_NO_THROW(validate_output_target("out", "pebble.v2"));

    // Through the whole run: nothing is written outside the output folder.
    const std::string parent = fresh("escape");
    OptimizeOptions options = options_for("escape/out", tiny_run(2, 1));
    options.name = "../x";
    EXPECT_NE(error_of([&] { run_optimize(options); }).find("--name '../x'"), std::string::npos);
    EXPECT_FALSE(fs::exists(parent + "/x_config.json"));
    options.name = "pebble";
    options.output_dir = "";
    EXPECT_NE(error_of([&] { run_optimize(options); }).find("-o/--output is empty"), std::string::npos);
}

TEST(RunGuard, SecondRunIntoALockedFolderIsRefusedInOneLine) {
    const std::string folder = fresh("locked");
    {
        const OutputFolderLock first(folder, "optimize");
        const std::string message = error_of([&] { OutputFolderLock second(folder, "optimize"); });
        EXPECT_NE(message.find("is in use by another tdf run (optimize on"), std::string::npos) << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        // A whole run into the locked folder stops before writing anything.
        const std::string run_message =
            error_of([&] { run_optimize(options_for("locked", tiny_run(2, 1))); });
        EXPECT_NE(run_message.find("in use by another tdf run"), std::string::npos) << run_message;
        EXPECT_FALSE(fs::exists(folder + "/pebble_config.json"));
    }
    // Released with the first holder.
    EXPECT_NO_THROW(OutputFolderLock again(folder, "optimize"));
}

TEST(RunGuard, StaleTemporariesAreRecognisedAndRemoved) {
    EXPECT_TRUE(is_atomic_temporary("pebble_albedo.tmp4242_3.png"));
    EXPECT_TRUE(is_atomic_temporary("checkpoint.tmp17_0.bin"));
    EXPECT_TRUE(is_atomic_temporary("summary.tmp17_12"));
    EXPECT_FALSE(is_atomic_temporary("pebble_albedo.png"));
    EXPECT_FALSE(is_atomic_temporary("view_000.exr"));
    EXPECT_FALSE(is_atomic_temporary("my.tmp_notes.txt"));
    const std::string folder = fresh("temporaries");
    fs::create_directories(folder + "/turntable");
    for (const char* f : {"pebble_albedo.tmp99999_0.png", "turntable/albedo_000.tmp99999_1.png", "keep.png"})
        write_text_atomically(folder + "/" + f, "x");
    const auto removed = remove_stale_temporaries(folder);
    EXPECT_EQ(removed.size(), 2u);
    EXPECT_TRUE(fs::exists(folder + "/keep.png"));
    EXPECT_FALSE(fs::exists(folder + "/pebble_albedo.tmp99999_0.png"));
}

TEST(RunGuard, CompletionRecordIsWrittenLastAndListsTheFilesWithHashes) {
    const std::string folder = fresh("complete");
    fs::create_directories(folder);
    // What a run killed during export leaves behind, and a record of an older run.
    write_text_atomically(folder + "/pebble_albedo.tmp77777_0.png", "partial");
    write_text_atomically(folder + "/pebble_complete.json", "{}");
    OptimizeOptions options = options_for("complete", tiny_run(3, 2));
    run_optimize(options);
    EXPECT_FALSE(fs::exists(folder + "/pebble_albedo.tmp77777_0.png"));
    const std::string record_path = completion_record_path(folder, "pebble");
    const Json record = load_json_file(record_path);
    EXPECT_EQ(record["command"], "optimize");
    EXPECT_GT(record["seconds"].get<double>(), 0.0);
    EXPECT_EQ(record["report"], "pebble_report.json");
    bool saw_obj = false, saw_lock = false;
    for (const Json& f : record["files"]) {
        const std::string path = f["path"].get<std::string>();
        saw_lock = saw_lock || path == kLockFileName;
        if (path == "pebble.obj") {
            saw_obj = true;
            EXPECT_EQ(f["fnv1a"].get<std::string>(), hash_hex(hash_file(folder + "/pebble.obj")));
            EXPECT_EQ(f["bytes"].get<std::uintmax_t>(), fs::file_size(folder + "/pebble.obj"));
        }
        // Every listed file exists and is no older than... the record itself.
        EXPECT_LE(fs::last_write_time(folder + "/" + path), fs::last_write_time(record_path)) << path;
    }
    EXPECT_TRUE(saw_obj);
    EXPECT_FALSE(saw_lock);
    // A new run into the folder removes the record first: the folder is incomplete until a run ends.
    OptimizeOptions partial = options;
    partial.stop_after = 1;
    run_optimize(partial);
    EXPECT_FALSE(fs::exists(record_path));
}

TEST(RunGuard, SigtermCheckpointsAtTheNextIterationAndResumeIsByteIdentical) {
    // checkpoint_every=0: before this fix a signal lost everything.
    fresh("straight");
    fresh("stopped");
    run_optimize(options_for("straight", tiny_run(5, 3)));

    const StopSignals signals;
    clear_stop_request();
    raise(SIGTERM);  // arrives while the run loads: it stops after its first iteration
    ASSERT_TRUE(stop_requested());
    const OptimizeOptions stopped = options_for("stopped", tiny_run(5, 3));
    try {
        run_optimize(stopped);
        FAIL() << "the run ignored SIGTERM";
    } catch (const RunInterrupted& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("interrupted by SIGTERM after iteration 1"), std::string::npos) << message;
        EXPECT_NE(message.find("--resume"), std::string::npos) << message;
    }
    const FieldCheckpoint checkpoint = load_field_checkpoint(stopped.output_dir + "/checkpoint.bin");
    EXPECT_EQ(parse_json(checkpoint.extra, "extra")["iteration"].get<int>(), 1);
    EXPECT_FALSE(fs::exists(completion_record_path(stopped.output_dir, "pebble")));

    clear_stop_request();
    OptimizeOptions resume = stopped;
    resume.resume = true;
    run_optimize(resume);
    const std::string a = test::scratch_dir() + "/run_guard/straight/pebble";
    const std::string b = stopped.output_dir + "/pebble";
    for (const char* suffix : {"_albedo.exr",
                               "_tactile_normal.exr",
                               "_albedo.png",
                               "_tactile_normal.png",
                               "_initialized_albedo.exr",
                               ".obj",
                               "_config.json"})
        EXPECT_EQ(read_text_file(a + suffix), read_text_file(b + suffix)) << suffix;
    EXPECT_TRUE(fs::exists(completion_record_path(stopped.output_dir, "pebble")));
}

TEST(RunGuard, SigintAlsoStopsWithACheckpoint) {
    fresh("sigint");
    const StopSignals signals;
    clear_stop_request();
    raise(SIGINT);
    try {
        run_optimize(options_for("sigint", tiny_run(4, 2)));
        FAIL() << "the run ignored SIGINT";
    } catch (const RunInterrupted& e) {
        EXPECT_NE(std::string(e.what()).find("SIGINT"), std::string::npos) << e.what();
    }
    clear_stop_request();
    EXPECT_TRUE(fs::exists(test::scratch_dir() + "/run_guard/sigint/checkpoint.bin"));
}

TEST(RunGuard, ResumeWithChangedInputsIsRefusedNamingThemAndKeepsTheConfig) {
    const std::string scene = copy_scene("inputs_scene");
    fresh("inputs");
    OptimizeOptions options = options_for("inputs", tiny_run(4, 2), scene);
    options.stop_after = 2;
    run_optimize(options);
    const std::string config_path = options.output_dir + "/pebble_config.json";
    const std::string config_before = read_text_file(config_path);

    // Same path, other content: the albedo image gets one different pixel.
    const std::string albedo = fs::path(scene).parent_path().string() + "/albedo.png";
    Image image = read_image(albedo);
    image.at(0, 0, 0) = image.at(0, 0, 0) > 0.5f ? 0.0f : 1.0f;
    write_png(albedo, image);
    options.resume = true;
    options.stop_after = 0;
    const std::string message = error_of([&] { run_optimize(options); });
    EXPECT_NE(message.find("input files changed"), std::string::npos) << message;
    EXPECT_NE(message.find("albedo.png changed"), std::string::npos) << message;
    EXPECT_EQ(message.find("sphere.obj"), std::string::npos) << message;
    EXPECT_EQ(read_text_file(config_path), config_before);

    // Another configuration is refused before the config file is touched as well.
    options.overrides.push_back("seed=9");
    const std::string config_message = error_of([&] { run_optimize(options); });
    EXPECT_NE(config_message.find("different scene or configuration (differs at: seed"), std::string::npos)
        << config_message;
    EXPECT_EQ(read_text_file(config_path), config_before);
}

TEST(RunGuard, SceneInputsFollowParentsAndMeshSidecars) {
    const SceneDescription scene = load_scene(kSceneFolder + "/scene.json");
    const std::vector<std::string> files = scene_input_files(scene, {"extra.png"});
    const auto has = [&](const std::string& suffix) {
        for (const std::string& f : files)
            if (f.size() >= suffix.size() && f.compare(f.size() - suffix.size(), suffix.size(), suffix) == 0)
                return true;
        return false;
    };
    EXPECT_TRUE(has("scene.json"));
    EXPECT_TRUE(has("sphere.obj"));
    EXPECT_TRUE(has("albedo.png"));
    EXPECT_TRUE(has("tactile_normal.png"));
    EXPECT_TRUE(has("extra.png"));
    const Json a = {{"x.png", "01"}, {"y.obj", "02"}};
    EXPECT_EQ(describe_input_changes(a, a), "");
    const Json b = {{"x.png", "09"}, {"z.png", "03"}};
    EXPECT_EQ(describe_input_changes(a, b),
              "x.png changed, y.obj is no longer an input, z.png is a new input");
}
