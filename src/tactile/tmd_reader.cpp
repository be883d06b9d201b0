#include <tdf/tactile/tmd_reader.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>

#include <cmath>
#include <cstdint>
#include <cstring>

namespace tdf {

namespace {

constexpr std::size_t kHeaderSize = 32;
constexpr const char kHeaderText[] = "Binary TrueMap Data File v2.0";

template <typename T>
T read_le(const std::string& bytes, std::size_t at) {
    T value;
    std::memcpy(&value, bytes.data() + at, sizeof(T));  // x86 and ARM hosts are little-endian
    return value;
}

}  // namespace

TmdFile read_tmd(const std::string& path) {
    const std::string bytes = read_text_file(path);
    if (bytes.size() < kHeaderSize || bytes.compare(0, sizeof(kHeaderText) - 1, kHeaderText) != 0)
        throw_error("{}: not a GelSight TrueMap v2.0 file (expected the header '{}')", path, kHeaderText);
    const std::size_t comment_end = bytes.find('\0', kHeaderSize);
    if (comment_end == std::string::npos) throw_error("{}: truncated .tmd header", path);
    std::size_t at = comment_end + 1;
    if (at + 24 > bytes.size()) throw_error("{}: truncated .tmd header", path);

    TmdFile file;
    file.comment = bytes.substr(kHeaderSize, comment_end - kHeaderSize);
    const std::uint32_t columns = read_le<std::uint32_t>(bytes, at);
    const std::uint32_t rows = read_le<std::uint32_t>(bytes, at + 4);
    file.length_x_mm = read_le<float>(bytes, at + 8);
    file.length_y_mm = read_le<float>(bytes, at + 12);
    file.offset_x_mm = read_le<float>(bytes, at + 16);
    file.offset_y_mm = read_le<float>(bytes, at + 20);
    at += 24;
    if (columns == 0 || rows == 0 || columns > 65536 || rows > 65536)
        throw_error("{}: implausible .tmd size {} x {}", path, columns, rows);
    if (!(file.length_x_mm > 0) || !(file.length_y_mm > 0) || !std::isfinite(file.length_x_mm) ||
        !std::isfinite(file.length_y_mm))
        throw_error(
            "{}: .tmd lengths must be positive, got {} x {} mm", path, file.length_x_mm, file.length_y_mm);
    const std::size_t count = std::size_t(columns) * rows;
    if (bytes.size() - at < count * 4)
        throw_error("{}: truncated .tmd data ({} of {} bytes)", path, bytes.size() - at, count * 4);

    file.map.height = Image(int(columns), int(rows), 1);
    std::memcpy(file.map.height.data(), bytes.data() + at, count * 4);
    if (!file.map.height.all_finite()) throw_error("{}: .tmd heights contain NaN or infinity", path);
    file.map.mm_per_pixel = file.length_x_mm / float(columns);
    file.map.source = path;
    const float mm_per_row = file.length_y_mm / float(rows);
    if (std::fabs(mm_per_row - file.map.mm_per_pixel) > 0.01f * file.map.mm_per_pixel)
        throw_error("{}: non-square .tmd pixels ({} x {} mm), not supported",
                    path,
                    file.map.mm_per_pixel,
                    mm_per_row);
    return file;
}

}  // namespace tdf
