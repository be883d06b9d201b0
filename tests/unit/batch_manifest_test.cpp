// Batch manifests (CSV and JSON lines), change detection, and `tdf batch grid`.
#include <gtest/gtest.h>
#include <tdf/batch/grid.h>
#include <tdf/batch/manifest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>

#include <filesystem>

#include "common/test_paths.h"

using namespace tdf;
namespace fs = std::filesystem;

namespace {
template <typename F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}
}  // namespace

TEST(BatchManifest, JsonLinesWithArrayAndStringArguments) {
    const auto jobs = parse_manifest(
        "# a comment\n"
        "{\"name\": \"a\", \"command\": \"optimize\", \"args\": [\"s.json\", \"views.orbit=[]\"], "
        "\"output\": \"x/a\"}\n"
        "\n"
        "{\"name\": \"b-2.v\", \"command\": \"render\", \"args\": \"s.json 'passes=[\\\"albedo\\\"]' "
        "--png\"}\n",
        "m.jsonl");
    ASSERT_EQ(jobs.size(), 2u);
    EXPECT_EQ(jobs[0].args, (std::vector<std::string>{"s.json", "views.orbit=[]"}));
    EXPECT_EQ(jobs[0].output, "x/a");
    EXPECT_EQ(jobs[1].args, (std::vector<std::string>{"s.json", "passes=[\"albedo\"]", "--png"}));
    EXPECT_EQ(jobs[1].output, "");
}

TEST(BatchManifest, CsvWithQuotedFieldsInAnyColumnOrder) {
    const auto jobs = parse_manifest(
        "command,name,args\n"
        "compare,c1,\"a.exr b.exr --fail 0.01\"\n"
        "tactile,t1,\"convert \"\"my file.npz\"\" -o {out}/n.png\"\n",
        "m.csv");
    ASSERT_EQ(jobs.size(), 2u);
    EXPECT_EQ(jobs[0].name, "c1");
    EXPECT_EQ(jobs[0].args, (std::vector<std::string>{"a.exr", "b.exr", "--fail", "0.01"}));
    EXPECT_EQ(jobs[1].args, (std::vector<std::string>{"convert", "my file.npz", "-o", "{out}/n.png"}));
    // CSV and JSON lines round-trip to the same jobs.
    EXPECT_TRUE(parse_manifest(manifest_to_csv(jobs), "x.csv") == jobs);
    EXPECT_TRUE(parse_manifest(manifest_to_jsonl(jobs), "x.jsonl") == jobs);
}

TEST(BatchManifest, BadManifestsAreOneLineErrorsWithTheLine) {
    EXPECT_NE(error_of([] { parse_manifest("", "m.csv"); }).find("m.csv: the manifest is empty"),
              std::string::npos);
    EXPECT_NE(error_of([] { parse_manifest("name,command\na,render\n", "m.csv"); }).find("no 'args' column"),
              std::string::npos);
    EXPECT_NE(error_of([] {
                  parse_manifest("name,command,args\na,paint,x\n", "m.csv");
              }).find("m.csv:2: job 'a': unknown command 'paint'"),
              std::string::npos);
    EXPECT_NE(error_of([] {
                  parse_manifest("name,command,args\n../a,render,x\n", "m.csv");
              }).find("job name '../a'"),
              std::string::npos);
    EXPECT_NE(error_of([] {
                  parse_manifest("name,command,args\na,render,x\na,render,y\n", "m.csv");
              }).find("m.csv:3: job name 'a' appears twice (first at m.csv:2)"),
              std::string::npos);
    EXPECT_NE(error_of([] {
                  parse_manifest("{\"name\":\"a\",\"command\":\"render\"}\n", "m.jsonl");
              }).find("m.jsonl:1: missing \"args\""),
              std::string::npos);
    EXPECT_NE(error_of([] {
                  parse_manifest("{\"name\":\"a\",\"command\":\"render\",\"args\":\"x\",\"gpu\":1}\n",
                                 "m.jsonl");
              }).find("unknown key 'gpu'"),
              std::string::npos);
    EXPECT_NE(error_of([] { split_arguments("a 'b", "here"); }).find("here: unclosed '"), std::string::npos);
    EXPECT_EQ(error_of([] { parse_manifest("name,command,args\na,render,s.json =3\n", "m.csv"); }),
              "m.csv:2: job 'a': override '=3' is not of the form key=value");
    EXPECT_EQ(error_of([] { parse_manifest("name,command,args\na,optimize,s.json seed..x=3\n", "m.csv"); }),
              "m.csv:2: job 'a': override 'seed..x=3' has an empty key component");
    // Only optimize and render take overrides.
    EXPECT_EQ(error_of([] { parse_manifest("name,command,args\na,tactile,convert =3\n", "m.csv"); }),
              "(no error)");
}

TEST(BatchManifest, MissingInputFilesNameTheRow) {
    const std::string dir = test::scratch_dir() + "/batch_manifest_inputs";
    fs::create_directories(dir);
    write_text_atomically(dir + "/s.json", "{}");
    const auto ok = parse_manifest(
        "name,command,args\n"
        "a,render,s.json image.width=8 -o views/x.png\n"
        "b,tactile,convert s.json -o {out}/n.png\n",
        "m.csv");
    EXPECT_NO_THROW(check_job_inputs(ok, dir));  // outputs (after -o, or with {out}) are not inputs
    const auto missing = parse_manifest(
        "name,command,args\n"
        "a,render,s.json\n"
        "b,compare,s.json gone.exr\n",
        "m.csv");
    EXPECT_EQ(error_of([&] { check_job_inputs(missing, dir); }),
              "m.csv:3: job 'b': input file 'gone.exr' does not exist (relative to " + dir + ")");
    const auto absolute =
        parse_manifest("name,command,args\na,optimize,s.json mesh=/no/such/mesh.obj\n", "m.csv");
    EXPECT_EQ(error_of([&] { check_job_inputs(absolute, dir); }),
              "m.csv:2: job 'a': input file '/no/such/mesh.obj' does not exist");
}

TEST(BatchManifest, ChangesAreNamed) {
    const auto before =
        parse_manifest("name,command,args\na,render,s.json\nb,render,s.json seed=1\n", "m.csv");
    EXPECT_EQ(describe_manifest_changes(before, before), "");
    auto after = before;
    after[1].args.back() = "seed=2";
    after.push_back(after[0]);
    after.back().name = "c";
    after.erase(after.begin());
    const std::string changes = describe_manifest_changes(before, after);
    EXPECT_NE(changes.find("job 'a' removed"), std::string::npos) << changes;
    EXPECT_NE(changes.find("job 'b': args differ (was: s.json seed=1; now: s.json seed=2)"),
              std::string::npos)
        << changes;
    EXPECT_NE(changes.find("job 'c' added"), std::string::npos) << changes;
    auto reordered = before;
    std::swap(reordered[0], reordered[1]);
    EXPECT_EQ(describe_manifest_changes(before, reordered), "the jobs are in another order");
}

TEST(BatchGrid, EveryObjectWithEveryTextureAndOverrideSet) {
    const std::string scene = test::source_dir() + "/scenes/pebble_sphere/scene.json";
    const std::string mesh = test::source_dir() + "/scenes/pebble_sphere/sphere.obj";
    const std::string texture = test::source_dir() + "/scenes/pebble_sphere/tactile_normal.png";
    GridSpec spec;
    spec.scenes = {scene, mesh};
    spec.base_scene = scene;
    spec.textures = {texture};
    spec.override_sets = {"seed=1", "seed=2 optimize.iterations=50"};
    const auto jobs = make_grid(spec);
    ASSERT_EQ(jobs.size(), 4u);
    EXPECT_EQ(jobs[0].name, "pebble_sphere_tactile_normal_0");
    EXPECT_EQ(jobs[3].name, "sphere_tactile_normal_1");
    EXPECT_EQ(jobs[0].args.front(), fs::absolute(scene).lexically_normal().string());
    EXPECT_EQ(jobs[1].args.back(), "optimize.iterations=50");
    EXPECT_EQ(jobs[2].args[1], "mesh=" + fs::absolute(mesh).lexically_normal().string());
    EXPECT_NE(jobs[0].args[1].find("tactile.images=[\""), std::string::npos);
    // A manifest file round trip.
    const std::string path = test::scratch_dir() + "/batch_grid/m.jsonl";
    write_text_atomically(path, manifest_to_jsonl(jobs));
    EXPECT_TRUE(read_manifest(path) == jobs);

    GridSpec no_base = spec;
    no_base.base_scene.clear();
    EXPECT_NE(error_of([&] { make_grid(no_base); }).find("--base-scene"), std::string::npos);
    GridSpec missing = spec;
    missing.textures = {"nothere.png"};
    EXPECT_NE(error_of([&] { make_grid(missing); }).find("texture 'nothere.png' does not exist"),
              std::string::npos);
}
