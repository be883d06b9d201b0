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
