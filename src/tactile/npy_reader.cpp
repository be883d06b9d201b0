#include <tdf/tactile/npy_reader.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>

namespace tdf {

double NpyArray::at(std::size_t row, std::size_t col, std::size_t channel) const {
    TDF_CHECK(shape.size() == 2 || shape.size() == 3);
    const std::size_t channels = shape.size() == 3 ? shape[2] : 1;
    return values[(row * shape[1] + col) * channels + channel];
}

namespace {

// ---- .npy ------------------------------------------------------------------------------------

// Value of `key` in the header dict, e.g. "'descr': '<f8'" -> "'<f8'" (raw text up to the
// next top-level comma or closing brace).
std::string header_value(const std::string& header, const std::string& key, const std::string& where) {
    const std::string quoted = "'" + key + "'";
    const auto k = header.find(quoted);
    if (k == std::string::npos) throw_error("{}: npy header has no '{}' entry", where, key);
    auto v = header.find(':', k + quoted.size());
    if (v == std::string::npos) throw_error("{}: malformed npy header", where);
    ++v;
    while (v < header.size() && header[v] == ' ') ++v;
    std::size_t end = v;
    if (v < header.size() && header[v] == '(') {
        end = header.find(')', v);
        if (end == std::string::npos) throw_error("{}: malformed npy shape", where);
        return header.substr(v, end + 1 - v);
    }
    while (end < header.size() && header[end] != ',' && header[end] != '}') ++end;
    std::string value = header.substr(v, end - v);
    while (!value.empty() && value.back() == ' ') value.pop_back();
    return value;
}

std::vector<std::size_t> parse_shape(const std::string& text, const std::string& where) {
    std::vector<std::size_t> shape;
    std::size_t i = 1;  // skip '('
    while (i < text.size()) {
        while (i < text.size() && (text[i] == ' ' || text[i] == ',')) ++i;
        if (i >= text.size() || text[i] == ')') break;
        if (!std::isdigit(static_cast<unsigned char>(text[i])))
            throw_error("{}: malformed npy shape {}", where, text);
        std::size_t value = 0;
        while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) {
            value = value * 10 + std::size_t(text[i] - '0');
            if (value > (std::size_t(1) << 40)) throw_error("{}: npy shape {} is too large", where, text);
            ++i;
        }
        shape.push_back(value);
    }
    return shape;
}

template <typename T>
T load_swapped(const unsigned char* p, bool swap) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, p, sizeof(T));
    if (swap) std::reverse(bytes, bytes + sizeof(T));
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
}

// IEEE half to float (numpy float16), including subnormals, infinities and NaN.
float half_to_float(std::uint16_t h) {
    const std::uint32_t sign = std::uint32_t(h & 0x8000u) << 16;
    const std::uint32_t exponent = (h >> 10) & 0x1fu;
    std::uint32_t mantissa = h & 0x3ffu;
    std::uint32_t bits;
    if (exponent == 0) {
        if (mantissa == 0) {
            bits = sign;
        } else {  // subnormal: renormalize
            int e = -1;
            do {
                ++e;
                mantissa <<= 1;
            } while ((mantissa & 0x400u) == 0);
            bits = sign | (std::uint32_t(127 - 15 - e) << 23) | ((mantissa & 0x3ffu) << 13);
        }
    } else if (exponent == 31) {
        bits = sign | 0x7f800000u | (mantissa << 13);
    } else {
        bits = sign | ((exponent + 127 - 15) << 23) | (mantissa << 13);
    }
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

// Converts `count` raw items of numpy kind `kind` ('f', 'i', 'u', 'b') and `size` bytes.
bool convert_values(char kind, int size, bool swap, const unsigned char* in, std::size_t count,
                    std::vector<double>& out) {
    out.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
        const unsigned char* p = in + i * std::size_t(size);
        double v;
        if (kind == 'f' && size == 8)
            v = load_swapped<double>(p, swap);
        else if (kind == 'f' && size == 4)
            v = load_swapped<float>(p, swap);
        else if (kind == 'f' && size == 2)
            v = half_to_float(load_swapped<std::uint16_t>(p, swap));
        else if (kind == 'i' && size == 1)
            v = double(static_cast<std::int8_t>(p[0]));
        else if (kind == 'i' && size == 2)
            v = load_swapped<std::int16_t>(p, swap);
        else if (kind == 'i' && size == 4)
            v = load_swapped<std::int32_t>(p, swap);
        else if (kind == 'i' && size == 8)
            v = double(load_swapped<std::int64_t>(p, swap));
        else if ((kind == 'u' || kind == 'b') && size == 1)
            v = p[0];
        else if (kind == 'u' && size == 2)
            v = load_swapped<std::uint16_t>(p, swap);
        else if (kind == 'u' && size == 4)
            v = load_swapped<std::uint32_t>(p, swap);
        else if (kind == 'u' && size == 8)
            v = double(load_swapped<std::uint64_t>(p, swap));
        else
            return false;
        out[i] = v;
    }
    return true;
}

// Fortran order -> C order for an array of any rank.
std::vector<double> fortran_to_c(const std::vector<double>& f, const std::vector<std::size_t>& shape) {
    std::vector<double> c(f.size());
    const std::size_t rank = shape.size();
    std::vector<std::size_t> index(rank, 0);
    for (std::size_t i = 0; i < f.size(); ++i) {
        // `index` is the multi-index of C-order position i; its Fortran offset:
        std::size_t offset = 0, stride = 1;
        for (std::size_t d = 0; d < rank; ++d) {
            offset += index[d] * stride;
            stride *= shape[d];
        }
        c[i] = f[offset];
        for (std::size_t d = rank; d-- > 0;) {
            if (++index[d] < shape[d]) break;
            index[d] = 0;
        }
    }
    return c;
}

// ---- .npz (zip) ------------------------------------------------------------------------------

std::uint16_t u16(const std::string& s, std::size_t at) {
    return std::uint16_t(std::uint8_t(s[at]) | (std::uint8_t(s[at + 1]) << 8));
}
std::uint32_t u32(const std::string& s, std::size_t at) {
    return std::uint32_t(u16(s, at)) | (std::uint32_t(u16(s, at + 2)) << 16);
}
std::uint64_t u64(const std::string& s, std::size_t at) {
    return std::uint64_t(u32(s, at)) | (std::uint64_t(u32(s, at + 4)) << 32);
}

// True when `length` bytes at `offset` lie inside `bytes`; offsets and lengths come from the
// file (ZIP64: 64-bit), so `offset + length` must not be computed before both are bounded.
bool fits(const std::string& bytes, std::uint64_t offset, std::uint64_t length) {
    return offset <= bytes.size() && length <= bytes.size() - offset;
}

std::string inflate_raw(const std::string& compressed, std::uint64_t size, const std::string& where) {
    // DEFLATE expands at most 1032:1; a larger claimed size is a corrupt header, refused before
    // allocating it.
    if (size > 1032 * std::uint64_t(compressed.size()) + 1024)
        throw_error(
            "{}: uncompressed size {} is impossible for {} compressed bytes", where, size, compressed.size());
    std::string out(size, '\0');
    z_stream stream{};
    if (inflateInit2(&stream, -MAX_WBITS) != Z_OK) throw_error("{}: cannot initialise zlib", where);
    stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
    stream.avail_in = uInt(compressed.size());
    stream.next_out = reinterpret_cast<Bytef*>(out.data());
    stream.avail_out = uInt(out.size());
    const int result = inflate(&stream, Z_FINISH);
    const bool complete = result == Z_STREAM_END && stream.total_out == size;
    inflateEnd(&stream);
    if (!complete) throw_error("{}: corrupt DEFLATE data (truncated archive?)", where);
    return out;
}

}  // namespace

NpyArray parse_npy(const std::string& bytes, const std::string& where) {
    static const char kMagic[] = "\x93NUMPY";
    if (bytes.size() < 10 || bytes.compare(0, 6, kMagic, 6) != 0) throw_error("{}: not a .npy array", where);
    const int major = std::uint8_t(bytes[6]);
    std::size_t header_length, header_start;
    if (major == 1) {
        header_length = u16(bytes, 8);
        header_start = 10;
    } else if (major == 2 || major == 3) {
        if (bytes.size() < 12) throw_error("{}: truncated .npy header", where);
        header_length = u32(bytes, 8);
        header_start = 12;
    } else {
        throw_error("{}: unsupported .npy format version {}", where, major);
    }
    if (header_start + header_length > bytes.size()) throw_error("{}: truncated .npy header", where);
    const std::string header = bytes.substr(header_start, header_length);

    NpyArray array;
    std::string descr = header_value(header, "descr", where);
    if (descr.size() < 2 || descr.front() != '\'' || descr.back() != '\'')
        throw_error("{}: unsupported dtype {} (structured arrays are not supported)", where, descr);
    array.dtype = descr.substr(1, descr.size() - 2);
    const bool fortran = header_value(header, "fortran_order", where) == "True";
    array.shape = parse_shape(header_value(header, "shape", where), where);

    const std::string& d = array.dtype;
    if (d.size() < 3 || (d[0] != '<' && d[0] != '>' && d[0] != '|' && d[0] != '='))
        throw_error("{}: unsupported dtype '{}'", where, d);
    const char kind = d[1];
    const int size = std::atoi(d.c_str() + 2);
    const bool swap = d[0] == '>';
    // Checked product: shape entries are bounded, their product may not be.
    std::size_t count = 1;
    for (std::size_t n : array.shape) {
        if (n != 0 && count > (bytes.size() + 1) / n)
            throw_error("{}: shape {} needs more data than the {} bytes present",
                        where,
                        header_value(header, "shape", where),
                        bytes.size());
        count *= n;
    }
    const std::size_t data_start = header_start + header_length;
    if (size <= 0 || size > 8) throw_error("{}: unsupported dtype '{}'", where, d);
    if ((bytes.size() - data_start) / std::size_t(size) < count)
        throw_error("{}: truncated data ({} bytes for {} values of '{}')",
                    where,
                    bytes.size() - data_start,
                    count,
                    d);
    if (!convert_values(kind,
                        size,
                        swap,
                        reinterpret_cast<const unsigned char*>(bytes.data() + data_start),
                        count,
                        array.values))
        throw_error("{}: unsupported dtype '{}' (expected float, integer or bool)", where, d);
    if (fortran && array.shape.size() > 1) array.values = fortran_to_c(array.values, array.shape);
    return array;
}

NpyArray read_npy(const std::string& path) { return parse_npy(read_text_file(path), path); }

std::map<std::string, NpyArray> read_npz(const std::string& path) {
    if (!std::filesystem::exists(path)) throw_error("cannot open '{}': no such file", path);
    const std::string zip = read_text_file(path);
    // End of central directory: 22 bytes plus a comment of at most 65535 bytes at the end.
    std::size_t eocd = std::string::npos;
    if (zip.size() >= 22) {
        const std::size_t lowest = zip.size() - 22 > 65535 ? zip.size() - 22 - 65535 : 0;
        for (std::size_t i = zip.size() - 22 + 1; i-- > lowest;)
            if (u32(zip, i) == 0x06054b50u) {
                eocd = i;
                break;
            }
    }
    if (eocd == std::string::npos) throw_error("{}: not a .npz (zip) archive, or truncated", path);
    std::uint64_t entries = u16(zip, eocd + 10);
    std::uint64_t directory = u32(zip, eocd + 16);
    if (directory == 0xffffffffu || entries == 0xffffu) {  // ZIP64 end of central directory
        if (eocd < 20 || u32(zip, eocd - 20) != 0x07064b50u) throw_error("{}: corrupt ZIP64 archive", path);
        const std::uint64_t record = u64(zip, eocd - 20 + 8);
        if (!fits(zip, record, 56) || u32(zip, std::size_t(record)) != 0x06064b50u)
            throw_error("{}: corrupt ZIP64 archive", path);
        entries = u64(zip, std::size_t(record) + 32);
        directory = u64(zip, std::size_t(record) + 48);
    }

    std::map<std::string, NpyArray> arrays;
    std::size_t at = std::size_t(directory);
    for (std::uint64_t e = 0; e < entries; ++e) {
        if (!fits(zip, at, 46) || u32(zip, at) != 0x02014b50u) throw_error("{}: corrupt zip directory", path);
        const std::uint16_t method = u16(zip, at + 10);
        const std::uint32_t crc = u32(zip, at + 16);
        std::uint64_t compressed = u32(zip, at + 20), uncompressed = u32(zip, at + 24);
        const std::size_t name_length = u16(zip, at + 28), extra_length = u16(zip, at + 30),
                          comment_length = u16(zip, at + 32);
        std::uint64_t local = u32(zip, at + 42);
        if (!fits(zip, at, 46 + std::uint64_t(name_length) + extra_length))
            throw_error("{}: corrupt zip directory", path);
        const std::string name = zip.substr(at + 46, name_length);
        // ZIP64 extra field: the 64-bit values follow in this order, only for saturated fields.
        for (std::size_t x = at + 46 + name_length; x + 4 <= at + 46 + name_length + extra_length;) {
            const std::uint16_t id = u16(zip, x), length = u16(zip, x + 2);
            std::size_t field = x + 4;
            // Each 64-bit value must lie inside this extra record (and so inside the file).
            const std::size_t record_end =
                std::min(x + 4 + std::size_t(length), at + 46 + name_length + extra_length);
            const auto take = [&](std::uint64_t& value) {
                if (value != 0xffffffffu) return;
                if (field + 8 > record_end) throw_error("{}: corrupt ZIP64 extra field", path);
                value = u64(zip, field);
                field += 8;
            };
            if (id == 0x0001) {
                take(uncompressed);
                take(compressed);
                take(local);
            }
            x += 4 + std::size_t(length);
        }
        at += 46 + name_length + extra_length + comment_length;

        const std::string where = path + ": " + name;
        if (!fits(zip, local, 30) || u32(zip, std::size_t(local)) != 0x04034b50u)
            throw_error("{}: corrupt zip entry (truncated archive?)", where);
        const std::uint64_t data =
            local + 30 + u16(zip, std::size_t(local) + 26) + u16(zip, std::size_t(local) + 28);
        if (!fits(zip, data, compressed)) throw_error("{}: member data is truncated", where);
        std::string member = zip.substr(std::size_t(data), std::size_t(compressed));
        if (method == 8) {
            member = inflate_raw(member, uncompressed, where);
        } else if (method != 0) {
            throw_error("{}: unsupported zip compression method {}", where, method);
        } else if (compressed != uncompressed) {
            throw_error("{}: corrupt zip entry sizes", where);
        }
        const std::uint32_t actual =
            std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(member.data()), uInt(member.size())));
        if (actual != crc)
            throw_error("{}: CRC mismatch (stored {:08x}, computed {:08x}): the archive is corrupt",
                        where,
                        crc,
                        actual);
        std::string key = name;
        if (key.size() > 4 && key.compare(key.size() - 4, 4, ".npy") == 0) key.resize(key.size() - 4);
        arrays[key] = parse_npy(member, where);
    }
    return arrays;
}

}  // namespace tdf
