#include <tdf/core/atomic_file.h>

#include <tdf/core/error.h>

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace tdf {

namespace fs = std::filesystem;

void ensure_folder(const std::string& folder) {
    if (folder.empty()) return;
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) throw_error("cannot create folder '{}': {}", folder, ec.message());
}

void check_output_file_name(const std::string& path) {
    std::error_code status_error;
    if (fs::is_directory(fs::path(path), status_error))
        throw_error("cannot write '{}': it is a folder, not a file name", path);
}

void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write) {
    static std::atomic<unsigned> counter{0};
    const fs::path final_path(path);
    check_output_file_name(path);
    ensure_folder(final_path.parent_path().string());
    const fs::path temporary = final_path.parent_path() /
                               (final_path.stem().string() + ".tmp" + std::to_string(getpid()) + "_" +
                                std::to_string(counter++) + final_path.extension().string());
    try {
        write(temporary.string());
    } catch (...) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        throw;
    }
    std::error_code ec;
    fs::rename(temporary, final_path, ec);
    if (ec) {
        const std::string reason = ec.message();  // before remove() reuses `ec`
        std::error_code ignored;
        fs::remove(temporary, ignored);
        throw_error("cannot write '{}': rename failed: {}", path, reason);
    }
}

void write_text_atomically(const std::string& path, const std::string& text) {
    write_atomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        if (!out) throw_error("cannot open '{}' for writing: {}", path, std::strerror(errno));
        out << text;
        out.flush();
        if (!out) throw_error("cannot write '{}': {} (disk full?)", path, std::strerror(errno));
    });
}

std::string read_text_file(const std::string& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw_error("cannot read '{}': it is a folder", path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw_error("cannot open '{}': {}", path, std::strerror(errno));
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace tdf
