#pragma once
// The command line every scene generator in tools/ shares: write the files, or regenerate them
// into a temporary folder and compare bytes with the committed ones (a ctest), so the committed
// files provably come from the generator's code.
//
//   <tool> <folder>            write the files
//   <tool> --check <folder>    exit 1 (naming each file) if a committed file differs
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <unistd.h>
#include <vector>

namespace tdf::tools {

/// `write_all(folder)` writes every file of `files` (paths relative to the folder).
inline int generator_main(int argc, char** argv, const char* tool, const std::vector<std::string>& files,
                          const std::function<void(const std::string&)>& write_all) {
    try {
        if (argc == 2) {
            write_all(argv[1]);
            return 0;
        }
        if (argc == 3 && std::string(argv[1]) == "--check") {
            const std::string fresh = (std::filesystem::temp_directory_path() /
                                       fmt::format("tdf_{}_check_{}", tool, std::uint64_t(::getpid())))
                                          .string();
            write_all(fresh);
            int differ = 0;
            for (const std::string& name : files) {
                const std::string committed = std::string(argv[2]) + "/" + name;
                if (!std::filesystem::exists(committed) ||
                    read_text_file(committed) != read_text_file(fresh + "/" + name)) {
                    std::fprintf(stderr, "%s differs from the generator's output\n", committed.c_str());
                    ++differ;
                }
            }
            std::filesystem::remove_all(fresh);
            return differ ? 1 : 0;
        }
        std::fprintf(stderr, "usage: %s <folder> | --check <folder>\n", argv[0]);
        return 2;
    } catch (const Error& e) {
        std::fprintf(stderr, "%s: %s\n", tool, e.what());
        return 1;
    }
}

}  // namespace tdf::tools
