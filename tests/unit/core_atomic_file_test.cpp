#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>

#include <filesystem>

#include "common/test_paths.h"

using namespace tdf;

TEST(AtomicFile, WritingOverAFolderNamesTheProblem) {
    const std::string folder = test::scratch_dir() + "/out_is_a_folder.json";
    std::filesystem::create_directories(folder);
    try {
        write_text_atomically(folder, "{}");
        FAIL() << "wrote over a folder";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find(folder), std::string::npos) << message;
        EXPECT_NE(message.find("it is a folder"), std::string::npos) << message;
        EXPECT_EQ(message.find("Success"), std::string::npos) << message;
    }
    EXPECT_TRUE(std::filesystem::is_directory(folder));
    // No temporary file left behind.
    std::size_t leftovers = 0;
    for (const auto& entry : std::filesystem::directory_iterator(test::scratch_dir()))
        if (entry.path().filename().string().find("out_is_a_folder.tmp") != std::string::npos) ++leftovers;
    EXPECT_EQ(leftovers, 0u);
    EXPECT_THROW(read_text_file(folder), Error);
}
