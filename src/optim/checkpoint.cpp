#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/hash.h>
#include <tdf/optim/checkpoint.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>

namespace tdf {

namespace {

constexpr char kMagic[8] = {'T', 'D', 'F', 'C', 'K', 'P', 'T', '\0'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderSize = 8 + 4 + 4 + 8 + 8 + 8;

template <typename T>
void append(std::string& out, const T& value) {
    out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
T read_at(const std::string& in, std::size_t pos) {
    T value;
    std::memcpy(&value, in.data() + pos, sizeof(T));
    return value;
}

}  // namespace

void save_field_checkpoint(const std::string& path, const std::vector<float>& parameters,
                           const AdamState& adam, const std::string& extra) {
    const std::string adam_bytes = adam.to_bytes();
    std::string out;
    out.reserve(kHeaderSize + parameters.size() * sizeof(float) + adam_bytes.size() + extra.size() + 8);
    out.append(kMagic, sizeof(kMagic));
    append(out, kVersion);
    append(out, std::uint32_t(0));
    append(out, std::uint64_t(parameters.size()));
    append(out, std::uint64_t(adam_bytes.size()));
    append(out, std::uint64_t(extra.size()));
    out.append(reinterpret_cast<const char*>(parameters.data()), parameters.size() * sizeof(float));
    out += adam_bytes;
    out += extra;
    append(out, fnv1a(out.data(), out.size()));
    write_atomically(path, [&](const std::string& temporary) {
        std::ofstream file(temporary, std::ios::binary);
        if (!file) throw_error("{}: cannot open for writing: {}", path, std::strerror(errno));
        file.write(out.data(), std::streamsize(out.size()));
        file.flush();
        if (!file) throw_error("{}: cannot write checkpoint: {} (disk full?)", path, std::strerror(errno));
    });
}

FieldCheckpoint load_field_checkpoint(const std::string& path) {
    const std::string in = read_text_file(path);
    if (in.size() < sizeof(kMagic) || std::memcmp(in.data(), kMagic, sizeof(kMagic)) != 0)
        throw_error("{}: not a tdf field checkpoint", path);
    if (in.size() < kHeaderSize + 8) throw_error("{}: checkpoint is truncated ({} bytes)", path, in.size());
    const auto version = read_at<std::uint32_t>(in, 8);
    if (version != kVersion)
        throw_error("{}: checkpoint version {} is not supported (expected {})", path, version, kVersion);
    const auto parameter_count = read_at<std::uint64_t>(in, 16);
    const auto adam_size = read_at<std::uint64_t>(in, 24);
    const auto extra_size = read_at<std::uint64_t>(in, 32);
    const std::uint64_t body = in.size() - kHeaderSize - 8;
    // Checked piecewise so that absurd sizes cannot overflow the sum.
    if (parameter_count > body / sizeof(float) || adam_size > body || extra_size > body ||
        parameter_count * sizeof(float) + adam_size + extra_size != body)
        throw_error(
            "{}: checkpoint is truncated or corrupt (sizes do not add up to {} bytes)", path, in.size());
    const std::size_t checksum_at = in.size() - 8;
    if (read_at<std::uint64_t>(in, checksum_at) != fnv1a(in.data(), checksum_at))
        throw_error("{}: checkpoint is corrupt (checksum mismatch)", path);

    FieldCheckpoint checkpoint;
    std::size_t pos = kHeaderSize;
    checkpoint.parameters.resize(parameter_count);
    std::memcpy(checkpoint.parameters.data(), in.data() + pos, parameter_count * sizeof(float));
    pos += parameter_count * sizeof(float);
    checkpoint.adam = AdamState::from_bytes(in.substr(pos, adam_size), path);
    pos += adam_size;
    checkpoint.extra = in.substr(pos, extra_size);
    if (checkpoint.adam.m.size() != parameter_count)
        throw_error("{}: checkpoint's Adam state has {} moments for {} parameters",
                    path,
                    checkpoint.adam.m.size(),
                    parameter_count);
    return checkpoint;
}

}  // namespace tdf
