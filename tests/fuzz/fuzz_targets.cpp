// Harness bodies: write the input where the reader expects a file, call the reader.
// Readers take paths (they name the file in every error), so each input goes through a small
// file in a per-process scratch folder; that costs a few microseconds per run.
#include "fuzz/fuzz_targets.h"

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/scene/scene_file.h>
#include <tdf/tactile/npy_reader.h>
#include <tdf/tactile/tmd_reader.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace tdf::fuzz {

namespace fs = std::filesystem;

namespace {

// A scratch folder per process, removed at exit.
class Scratch {
public:
    Scratch() {
        // Memory-backed when available: the harnesses write one small file per input.
        std::error_code ec;
        const fs::path base =
            fs::is_directory("/dev/shm", ec) ? fs::path("/dev/shm") : fs::temp_directory_path();
        m_folder = base / ("tdf_fuzz_" + std::to_string(getpid()));
        fs::create_directories(m_folder);
    }
    ~Scratch() {
        std::error_code ignored;
        fs::remove_all(m_folder, ignored);
    }
    std::string file(const std::string& name) const { return (m_folder / name).string(); }

private:
    fs::path m_folder;
};

const Scratch& scratch() {
    static const Scratch s;
    return s;
}

std::string write_file(const std::string& name, const std::string& bytes) {
    const std::string path = scratch().file(name);
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    return path;
}

void remove_file(const std::string& name) {
    std::error_code ignored;
    fs::remove(scratch().file(name), ignored);
}

// Splits `bytes` at kPartSeparator into at most `max_parts` parts (the last keeps the rest).
std::vector<std::string> split_parts(const std::string& bytes, std::size_t max_parts) {
    std::vector<std::string> parts;
    const std::string separator = kPartSeparator;
    std::size_t start = 0;
    while (parts.size() + 1 < max_parts) {
        const auto at = bytes.find(separator, start);
        if (at == std::string::npos) break;
        parts.push_back(bytes.substr(start, at - start));
        start = at + separator.size();
    }
    parts.push_back(bytes.substr(start));
    return parts;
}

std::string as_string(const std::uint8_t* data, std::size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
}

// OBJ, then optionally "----" and the MTL found beside it (in.mtl, the OBJ's stem).
void fuzz_obj(const std::uint8_t* data, std::size_t size) {
    const auto parts = split_parts(as_string(data, size), 2);
    if (parts.size() > 1)
        write_file("in.mtl", parts[1]);
    else
        remove_file("in.mtl");
    load_obj(write_file("in.obj", parts[0]));
}

// A .glb when the input starts with the GLB magic; otherwise .gltf JSON, then optionally
// "----" and the buffer file in.bin.
void fuzz_gltf(const std::uint8_t* data, std::size_t size) {
    const std::string bytes = as_string(data, size);
    if (bytes.rfind("glTF", 0) == 0) {
        load_gltf(write_file("in.glb", bytes));
        return;
    }
    const auto parts = split_parts(bytes, 2);
    if (parts.size() > 1)
        write_file("in.bin", parts[1]);
    else
        remove_file("in.bin");
    load_gltf(write_file("in.gltf", parts[0]));
}

void fuzz_ply(const std::uint8_t* data, std::size_t size) {
    load_ply(write_file("in.ply", as_string(data, size)));
}

// PNG, JPEG or EXR by content, as `read_image` and `read_exr_layers` see them.
void fuzz_image(const std::uint8_t* data, std::size_t size) {
    const std::string path = write_file("in.img", as_string(data, size));
    ImageMetadata metadata;
    try {
        read_image(path, metadata);
    } catch (const Error&) {
    }
    if (size >= 4 && data[0] == 0x76 && data[1] == 0x2f && data[2] == 0x31 && data[3] == 0x01)
        read_exr_layers(path);
}

// A .npy image (parsed from memory), or a .npz archive when the input starts with "PK".
void fuzz_npy(const std::uint8_t* data, std::size_t size) {
    const std::string bytes = as_string(data, size);
    if (bytes.rfind("PK", 0) == 0)
        read_npz(write_file("in.npz", bytes));
    else
        parse_npy(bytes, "in.npy");
}

void fuzz_tmd(const std::uint8_t* data, std::size_t size) {
    read_tmd(write_file("in.tmd", as_string(data, size)));
}

// scene.json, then optionally "----" and key=value overrides one per line, then optionally
// "----" and base.json (reachable through "parent": "base.json").
void fuzz_scene(const std::uint8_t* data, std::size_t size) {
    const auto parts = split_parts(as_string(data, size), 3);
    std::vector<std::string> overrides;
    if (parts.size() > 1) {
        std::size_t start = 0;
        while (start <= parts[1].size()) {
            auto end = parts[1].find('\n', start);
            if (end == std::string::npos) end = parts[1].size();
            if (end > start) overrides.push_back(parts[1].substr(start, end - start));
            start = end + 1;
        }
    }
    if (parts.size() > 2)
        write_file("base.json", parts[2]);
    else
        remove_file("base.json");
    load_scene(write_file("scene.json", parts[0]), overrides);
}

}  // namespace

const std::vector<Target>& targets() {
    static const std::vector<Target> list = {
        {"obj", fuzz_obj},
        {"gltf", fuzz_gltf},
        {"ply", fuzz_ply},
        {"image", fuzz_image},
        {"npy", fuzz_npy},
        {"tmd", fuzz_tmd},
        {"scene", fuzz_scene},
    };
    return list;
}

const Target* find_target(const std::string& name) {
    for (const auto& t : targets())
        if (name == t.name) return &t;
    return nullptr;
}

void run_one(const Target& target, const std::uint8_t* data, std::size_t size) {
    try {
        target.function(data, size);
    } catch (const Error&) {
        // The documented outcome for bad input.
    }
}

}  // namespace tdf::fuzz
