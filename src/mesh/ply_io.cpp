// PLY reading (ASCII, binary little- and big-endian). Hand-written: the format is small, and every
// error must name the file and the element. Vertex colours may be uchar (/255), ushort (/65535)
// or float; UVs may be per vertex (s t, u v, texture_u texture_v) or per face corner (MeshLab's
// `property list uchar float texcoord`). Polygons are fanned from their first corner like OBJ.
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/mesh/mesh_io.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string_view>

namespace tdf {

namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class PlyFormat { Ascii, BinaryLittle, BinaryBig };

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;
    bool is_list = false;
    PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
    std::string name;
    std::size_t count = 0;
    std::vector<PlyProperty> properties;
    int find(std::string_view property) const {
        for (std::size_t i = 0; i < properties.size(); ++i)
            if (properties[i].name == property) return int(i);
        return -1;
    }
};

bool parse_type(const std::string& name, PlyType& type) {
    static const std::pair<const char*, PlyType> kTypes[] = {{"char", PlyType::Int8},
                                                             {"int8", PlyType::Int8},
                                                             {"uchar", PlyType::UInt8},
                                                             {"uint8", PlyType::UInt8},
                                                             {"short", PlyType::Int16},
                                                             {"int16", PlyType::Int16},
                                                             {"ushort", PlyType::UInt16},
                                                             {"uint16", PlyType::UInt16},
                                                             {"int", PlyType::Int32},
                                                             {"int32", PlyType::Int32},
                                                             {"uint", PlyType::UInt32},
                                                             {"uint32", PlyType::UInt32},
                                                             {"float", PlyType::Float32},
                                                             {"float32", PlyType::Float32},
                                                             {"double", PlyType::Float64},
                                                             {"float64", PlyType::Float64}};
    for (const auto& [n, t] : kTypes)
        if (name == n) {
            type = t;
            return true;
        }
    return false;
}

std::size_t type_size(PlyType t) {
    switch (t) {
        case PlyType::Int8:
        case PlyType::UInt8:
            return 1;
        case PlyType::Int16:
        case PlyType::UInt16:
            return 2;
        case PlyType::Int32:
        case PlyType::UInt32:
        case PlyType::Float32:
            return 4;
        case PlyType::Float64:
            return 8;
    }
    return 4;
}

// Reads values one at a time from the body, ASCII tokens or binary of either byte order.
class PlyReader {
public:
    PlyReader(const std::string& data, std::size_t offset, PlyFormat format, const std::string& path)
        : m_data(data), m_pos(offset), m_format(format), m_path(path) {}

    double read(PlyType type, const char* where, std::size_t index) {
        if (m_format == PlyFormat::Ascii) return read_ascii(where, index);
        const std::size_t size = type_size(type);
        if (m_pos + size > m_data.size())
            throw_error("{}: the file ends inside {} {} (truncated?)", m_path, where, index);
        unsigned char bytes[8];
        std::memcpy(bytes, m_data.data() + m_pos, size);
        m_pos += size;
        if (m_format == PlyFormat::BinaryBig)
            for (std::size_t i = 0; i < size / 2; ++i) std::swap(bytes[i], bytes[size - 1 - i]);
        switch (type) {
            case PlyType::Int8:
                return double(std::int8_t(bytes[0]));
            case PlyType::UInt8:
                return double(bytes[0]);
            case PlyType::Int16:
                return double(load<std::int16_t>(bytes));
            case PlyType::UInt16:
                return double(load<std::uint16_t>(bytes));
            case PlyType::Int32:
                return double(load<std::int32_t>(bytes));
            case PlyType::UInt32:
                return double(load<std::uint32_t>(bytes));
            case PlyType::Float32:
                return double(load<float>(bytes));
            case PlyType::Float64:
                return load<double>(bytes);
        }
        return 0.0;
    }

private:
    template <typename T>
    static T load(const unsigned char* bytes) {
        T value;
        std::memcpy(&value, bytes, sizeof(T));  // the host is little-endian (x86-64, aarch64)
        return value;
    }
    double read_ascii(const char* where, std::size_t index) {
        while (m_pos < m_data.size() && std::isspace(static_cast<unsigned char>(m_data[m_pos]))) ++m_pos;
        const std::size_t begin = m_pos;
        while (m_pos < m_data.size() && !std::isspace(static_cast<unsigned char>(m_data[m_pos]))) ++m_pos;
        if (begin == m_pos) throw_error("{}: the file ends inside {} {} (truncated?)", m_path, where, index);
        double value = 0;
        const auto result = std::from_chars(m_data.data() + begin, m_data.data() + m_pos, value);
        if (result.ec != std::errc() || result.ptr != m_data.data() + m_pos)
            throw_error("{}: {} {} has '{}', which is not a number",
                        m_path,
                        where,
                        index,
                        m_data.substr(begin, std::min<std::size_t>(m_pos - begin, 32)));
        return value;
    }

    const std::string& m_data;
    std::size_t m_pos;
    PlyFormat m_format;
    const std::string& m_path;
};

// Finds the first property named like one of `names` (returns -1 when none).
int find_any(const PlyElement& e, std::initializer_list<const char*> names) {
    for (const char* n : names)
        if (const int i = e.find(n); i >= 0) return i;
    return -1;
}

// The header: lines up to "end_header", its elements and format, and where the body starts.
struct PlyHeader {
    std::vector<PlyElement> elements;
    PlyFormat format = PlyFormat::Ascii;
    std::size_t body = 0;
};

PlyHeader parse_ply_header(const std::string& data, const std::string& path) {
    if (data.compare(0, 3, "ply") != 0)
        throw_error("{}: not a PLY file (it does not start with 'ply')", path);
    const std::size_t header_end = data.find("end_header");
    if (header_end == std::string::npos) throw_error("{}: PLY header has no 'end_header'", path);
    std::size_t body = data.find('\n', header_end);
    body = body == std::string::npos ? data.size() : body + 1;
    std::istringstream header(data.substr(0, header_end));
    PlyHeader result;
    std::vector<PlyElement>& elements = result.elements;
    PlyFormat& format = result.format;
    bool have_format = false;
    std::string line;
    std::size_t line_number = 0;
    while (std::getline(header, line)) {
        ++line_number;
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword.empty() || keyword == "ply" || keyword == "comment" || keyword == "obj_info") continue;
        if (keyword == "format") {
            std::string name;
            words >> name;
            if (name == "ascii")
                format = PlyFormat::Ascii;
            else if (name == "binary_little_endian")
                format = PlyFormat::BinaryLittle;
            else if (name == "binary_big_endian")
                format = PlyFormat::BinaryBig;
            else
                throw_error("{}:{}: unknown PLY format '{}'", path, line_number, name);
            have_format = true;
        } else if (keyword == "element") {
            PlyElement e;
            long long count = -1;
            words >> e.name >> count;
            if (e.name.empty() || count < 0)
                throw_error("{}:{}: malformed element line '{}'", path, line_number, line);
            // Every item takes at least one byte: a larger count is a corrupt header, not a
            // reason to reserve gigabytes.
            if (std::size_t(count) > data.size())
                throw_error("{}:{}: element '{}' declares {} items but the file has only {} bytes",
                            path,
                            line_number,
                            e.name,
                            count,
                            data.size());
            e.count = std::size_t(count);
            elements.push_back(e);
        } else if (keyword == "property") {
            if (elements.empty()) throw_error("{}:{}: property before any element", path, line_number);
            PlyProperty p;
            std::string type;
            words >> type;
            if (type == "list") {
                std::string count_type, item_type;
                words >> count_type >> item_type >> p.name;
                p.is_list = true;
                if (!parse_type(count_type, p.count_type) || !parse_type(item_type, p.type))
                    throw_error(
                        "{}:{}: unknown PLY list types '{} {}'", path, line_number, count_type, item_type);
            } else {
                words >> p.name;
                if (!parse_type(type, p.type))
                    throw_error("{}:{}: unknown PLY type '{}'", path, line_number, type);
            }
            if (p.name.empty()) throw_error("{}:{}: property without a name", path, line_number);
            elements.back().properties.push_back(p);
        } else {
            throw_error("{}:{}: unexpected PLY header line '{}'", path, line_number, line);
        }
    }
    if (!have_format) throw_error("{}: PLY header has no 'format' line", path);
    result.body = body;
    return result;
}

}  // namespace

TriangleMesh load_ply(const std::string& path, const MeshLoadOptions& options) {
    const std::string data = read_text_file(path);
    const PlyHeader header = parse_ply_header(data, path);
    const std::vector<PlyElement>& elements = header.elements;
    TriangleMesh mesh;
    mesh.source_path = path;
    std::vector<Vec2f> vertex_uvs;
    bool corner_uvs = false;
    PlyReader reader(data, header.body, header.format, path);
    bool have_vertices = false, have_faces = false;
    for (const PlyElement& e : elements) {
        const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
        int x = -1, y = -1, z = -1, r = -1, g = -1, b = -1, u = -1, v = -1, indices = -1, texcoords = -1;
        if (is_vertex) {
            have_vertices = true;
            x = e.find("x"), y = e.find("y"), z = e.find("z");
            if (x < 0 || y < 0 || z < 0) throw_error("{}: PLY vertex element lacks x, y or z", path);
            r = find_any(e, {"red", "r", "diffuse_red"});
            g = find_any(e, {"green", "g", "diffuse_green"});
            b = find_any(e, {"blue", "b", "diffuse_blue"});
            if (!(r >= 0 && g >= 0 && b >= 0)) r = g = b = -1;
            u = find_any(e, {"s", "u", "texture_u"});
            v = find_any(e, {"t", "v", "texture_v"});
            if (!(u >= 0 && v >= 0)) u = v = -1;
            mesh.positions.reserve(e.count);
            if (r >= 0) mesh.colors.reserve(e.count);
        }
        if (is_face) {
            have_faces = true;
            indices = find_any(e, {"vertex_indices", "vertex_index"});
            if (indices < 0 || !e.properties[std::size_t(indices)].is_list)
                throw_error("{}: PLY face element lacks a 'vertex_indices' list", path);
            texcoords = e.find("texcoord");
            if (texcoords >= 0 && !e.properties[std::size_t(texcoords)].is_list) texcoords = -1;
            corner_uvs = texcoords >= 0;
        }
        const auto colour_scale = [&](int p) {
            const PlyType t = e.properties[std::size_t(p)].type;
            return t == PlyType::UInt8 ? 1.0 / 255.0 : t == PlyType::UInt16 ? 1.0 / 65535.0 : 1.0;
        };
        std::vector<double> values(e.properties.size());
        std::vector<int> polygon;
        std::vector<double> polygon_uvs;
        for (std::size_t item = 0; item < e.count; ++item) {
            const char* where = is_vertex ? "vertex" : is_face ? "face" : e.name.c_str();
            for (std::size_t p = 0; p < e.properties.size(); ++p) {
                const PlyProperty& prop = e.properties[p];
                if (!prop.is_list) {
                    values[p] = reader.read(prop.type, where, item);
                    continue;
                }
                const double count = reader.read(prop.count_type, where, item);
                if (!(count >= 0 && count <= 1e6))
                    throw_error("{}: {} {} has a list of {} items", path, where, item, count);
                if (int(p) == indices) polygon.assign(std::size_t(count), 0);
                if (int(p) == texcoords) polygon_uvs.assign(std::size_t(count), 0.0);
                for (std::size_t k = 0; k < std::size_t(count); ++k) {
                    const double value = reader.read(prop.type, where, item);
                    if (int(p) == indices) {
                        if (value < 0 || value >= double(mesh.positions.size()) || value != std::floor(value))
                            throw_error("{}: face {} uses vertex {} but the file has {} vertices",
                                        path,
                                        item,
                                        value,
                                        mesh.positions.size());
                        polygon[k] = int(value);
                    }
                    if (int(p) == texcoords) polygon_uvs[k] = value;
                }
            }
            if (is_vertex) {
                mesh.positions.emplace_back(float(values[std::size_t(x)]),
                                            float(values[std::size_t(y)]),
                                            float(values[std::size_t(z)]));
                if (r >= 0)
                    mesh.colors.emplace_back(float(values[std::size_t(r)] * colour_scale(r)),
                                             float(values[std::size_t(g)] * colour_scale(g)),
                                             float(values[std::size_t(b)] * colour_scale(b)));
                if (u >= 0)
                    vertex_uvs.emplace_back(float(values[std::size_t(u)]), float(values[std::size_t(v)]));
            } else if (is_face) {
                if (polygon.size() < 3)
                    throw_error("{}: face {} has {} corners, at least 3 needed", path, item, polygon.size());
                if (corner_uvs && polygon_uvs.size() != 2 * polygon.size())
                    throw_error("{}: face {} has {} texcoord values for {} corners",
                                path,
                                item,
                                polygon_uvs.size(),
                                polygon.size());
                const int first_uv = int(mesh.uvs.size());
                if (corner_uvs)
                    for (std::size_t k = 0; k < polygon.size(); ++k)
                        mesh.uvs.emplace_back(float(polygon_uvs[2 * k]), float(polygon_uvs[2 * k + 1]));
                for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
                    mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
                    if (corner_uvs)
                        mesh.uv_triangles.push_back({first_uv, first_uv + int(k), first_uv + int(k) + 1});
                }
            }
        }
    }
    if (!have_vertices) throw_error("{}: PLY file has no vertex element", path);
    if (!have_faces) throw_error("{}: PLY file has no face element (point clouds are not meshes)", path);
    if (!corner_uvs && !vertex_uvs.empty()) {
        mesh.uvs = std::move(vertex_uvs);
        mesh.uv_triangles = mesh.triangles;
    }
    finish_loaded_mesh(mesh, path, options);
    return mesh;
}

}  // namespace tdf
