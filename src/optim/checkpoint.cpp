#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/hash.h>
#include <tdf/optim/checkpoint.h>

#include <cerrno>
#include <cstdint>
#include <algorithm>
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
    CheckpointPieces pieces;
    pieces.parameters = {{parameters.data(), parameters.size()}};
    pieces.m = {{adam.m.data(), adam.m.size()}};
    pieces.v = {{adam.v.data(), adam.v.size()}};
    pieces.step = adam.step;
    save_field_checkpoint(path, pieces, extra);
}

void save_field_checkpoint(const std::string& path, const CheckpointPieces& pieces, const std::string& extra) {
    const auto count = [](const std::vector<FloatRange>& ranges) {
        std::uint64_t n = 0;
        for (const FloatRange& r : ranges) n += r.size;
        return n;
    };
    const std::uint64_t parameter_count = count(pieces.parameters);
    TDF_CHECK_EQ(count(pieces.m), parameter_count);
    TDF_CHECK_EQ(count(pieces.v), parameter_count);
    std::string header;
    header.append(kMagic, sizeof(kMagic));
    append(header, kVersion);
    append(header, std::uint32_t(0));
    append(header, parameter_count);
    append(header, AdamState::blob_size(parameter_count));
    append(header, std::uint64_t(extra.size()));
    write_atomically(path, [&](const std::string& temporary) {
        std::ofstream file(temporary, std::ios::binary);
        if (!file) throw_error("{}: cannot open for writing: {}", path, std::strerror(errno));
        std::uint64_t checksum = kFnv1aSeed;
        const auto put = [&](const char* bytes, std::size_t size) {
            checksum = fnv1a(bytes, size, checksum);
            file.write(bytes, std::streamsize(size));
        };
        const auto put_ranges = [&](const std::vector<FloatRange>& ranges) {
            static const std::vector<float> zeros(1 << 14, 0.0f);
            for (const FloatRange& r : ranges) {
                if (r.data) {
                    put(reinterpret_cast<const char*>(r.data), r.size * sizeof(float));
                    continue;
                }
                // A range of zeros (the Jacobi residual's moments: over half of a texture-space
                // checkpoint) is hashed in closed form, the same checksum without a pass a byte.
                checksum = fnv1a_zeros(r.size * sizeof(float), checksum);
                for (std::size_t done = 0; done < r.size; done += zeros.size())
                    file.write(reinterpret_cast<const char*>(zeros.data()),
                               std::streamsize(std::min(zeros.size(), r.size - done) * sizeof(float)));
            }
        };
        put(header.data(), header.size());
        put_ranges(pieces.parameters);
        const std::string adam_header = AdamState::blob_header(parameter_count, pieces.step);
        put(adam_header.data(), adam_header.size());
        put_ranges(pieces.m);
        put_ranges(pieces.v);
        put(extra.data(), extra.size());
        file.write(reinterpret_cast<const char*>(&checksum), sizeof(checksum));
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
