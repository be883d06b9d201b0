#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/optim/checkpoint.h>

#include <filesystem>
#include <fstream>

#include "common/test_paths.h"

using namespace tdf;

namespace {

std::string write_bytes(const std::string& name, const std::string& bytes) {
    const std::string path = test::scratch_dir() + "/" + name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

}  // namespace

TEST(Checkpoint, RoundTripIsExact) {
    std::vector<float> params = {1.5f, -2.0f, 3.25f, 1e-30f};
    Adam adam(params.size());
    adam.step(params, {0.1f, 0.2f, -0.3f, 0.0f});
    const std::string path = test::scratch_dir() + "/roundtrip.ckpt";
    save_field_checkpoint(path, params, adam.state(), R"({"iteration": 7})");
    const FieldCheckpoint loaded = load_field_checkpoint(path);
    EXPECT_EQ(loaded.parameters, params);
    EXPECT_TRUE(loaded.adam == adam.state());
    EXPECT_EQ(loaded.extra, R"({"iteration": 7})");
    // No temporary files are left beside it.
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(test::scratch_dir()))
        files += entry.path().filename().string().rfind("roundtrip", 0) == 0;
    EXPECT_EQ(files, 1);
}

TEST(Checkpoint, PiecesWriteTheSameBytesAsTheConcatenatedForm) {
    // A trainer streams its field and its residual (whose moments may be implicit zeros) as
    // pieces; the file must be the one the concatenated vectors give.
    const std::vector<float> field = {1.0f, -2.0f, 3.0f}, residual = {0.25f, 0.5f};
    AdamState field_state;
    field_state.m = {0.1f, 0.2f, 0.3f};
    field_state.v = {0.01f, 0.02f, 0.03f};
    field_state.step = 12;
    AdamState whole = field_state;
    whole.m.insert(whole.m.end(), {0.0f, 0.0f});
    whole.v.insert(whole.v.end(), {0.0f, 0.0f});
    std::vector<float> all = field;
    all.insert(all.end(), residual.begin(), residual.end());
    const std::string concatenated = test::scratch_dir() + "/concatenated.ckpt";
    save_field_checkpoint(concatenated, all, whole, "extra");

    CheckpointPieces pieces;
    pieces.parameters = {{field.data(), field.size()}, {residual.data(), residual.size()}};
    pieces.m = {{field_state.m.data(), 3}, {nullptr, 2}};
    pieces.v = {{field_state.v.data(), 3}, {nullptr, 2}};
    pieces.step = 12;
    const std::string streamed = test::scratch_dir() + "/streamed.ckpt";
    save_field_checkpoint(streamed, pieces, "extra");
    EXPECT_EQ(read_text_file(streamed), read_text_file(concatenated));
    const FieldCheckpoint loaded = load_field_checkpoint(streamed);
    EXPECT_EQ(loaded.parameters, all);
    EXPECT_TRUE(loaded.adam == whole);
}

TEST(Checkpoint, DamagedFilesAreRejectedWithTheirName) {
    std::vector<float> params(100, 0.5f);
    const std::string good = test::scratch_dir() + "/good.ckpt";
    save_field_checkpoint(good, params, Adam(100).state());
    const std::string bytes = read_text_file(good);

    const std::string truncated = write_bytes("truncated.ckpt", bytes.substr(0, bytes.size() - 100));
    std::string flipped = bytes;
    flipped[200] = char(flipped[200] ^ 0x10);
    const std::string corrupt = write_bytes("corrupt.ckpt", flipped);
    const std::string other =
        write_bytes("other.ckpt", "P6 not a checkpoint at all, but long enough to have a header");
    std::string future = bytes;
    future[8] = 9;
    const std::string version = write_bytes("version.ckpt", future);
    for (const std::string& path :
         {truncated, corrupt, other, version, test::scratch_dir() + "/missing.ckpt"}) {
        try {
            load_field_checkpoint(path);
            ADD_FAILURE() << path << " was accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        }
    }
}
