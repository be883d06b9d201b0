// Wavefront OBJ/MTL reading. Hand-written rather than tinyobjloader because the reference's
// semantics matter (separate position/UV index buffers, the last map_Kd wins, xyzrgb vertices,
// its MTL search order, spec 1.2) and every error must name the file and line.
#include <tdf/mesh/mesh_io.h>

#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>

namespace tdf {

namespace fs = std::filesystem;

namespace {

class LineParser {
public:
    LineParser(std::string_view line, const std::string& path, std::size_t line_number)
        : m_rest(line), m_path(path), m_line(line_number) {}

    std::string_view next_token() {
        skip_space();
        std::size_t end = 0;
        while (end < m_rest.size() && !is_space(m_rest[end])) ++end;
        std::string_view token = m_rest.substr(0, end);
        m_rest.remove_prefix(end);
        return token;
    }
    std::string_view rest_trimmed() {
        skip_space();
        std::string_view r = m_rest;
        while (!r.empty() && is_space(r.back())) r.remove_suffix(1);
        return r;
    }
    float next_float(const char* what) {
        const std::string_view token = next_token();
        if (token.empty()) fail("{} is missing a number", what);
        float value = 0;
        // std::from_chars for float is in libstdc++ 11+.
        const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
        if (result.ec != std::errc() || result.ptr != token.data() + token.size()) {
            // Accept "nan"/"inf" spellings from_chars rejects, so they are reported as non-finite.
            const std::string copy(token);
            char* end = nullptr;
            value = std::strtof(copy.c_str(), &end);
            if (end != copy.c_str() + copy.size()) fail("{} has '{}', which is not a number", what, copy);
        }
        if (!std::isfinite(value)) fail("{} has a non-finite value '{}'", what, std::string(token));
        return value;
    }
    bool at_end() {
        skip_space();
        return m_rest.empty();
    }
    template <typename... Args>
    [[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) const {
        throw_error("{}:{}: {}", m_path, m_line, fmt::format(format, std::forward<Args>(args)...));
    }

private:
    static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }
    void skip_space() {
        while (!m_rest.empty() && is_space(m_rest.front())) m_rest.remove_prefix(1);
    }

    std::string_view m_rest;
    const std::string& m_path;
    std::size_t m_line;
};

// OBJ indices: 1-based, negative = relative to the current end of the list.
int resolve_index(std::string_view text, std::size_t count, const LineParser& parser, const char* what) {
    int value = 0;
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    if (result.ec != std::errc() || result.ptr != text.data() + text.size() || value == 0)
        parser.fail("invalid {} index '{}'", what, std::string(text));
    const long resolved = value > 0 ? long(value) - 1 : long(count) + long(value);
    if (resolved < 0 || resolved >= long(count))
        parser.fail("{} index {} is out of range ({} defined so far)", what, value, count);
    return int(resolved);
}

// Finds the albedo texture named by the MTL, in the reference's search order (spec 1.2).
std::string find_albedo_texture(const fs::path& obj_path, const std::string& mtllib) {
    const fs::path folder = obj_path.parent_path();
    std::vector<fs::path> candidates;
    if (!mtllib.empty()) {
        candidates.push_back(mtllib);
        candidates.push_back(folder / mtllib);
    }
    candidates.push_back(folder / (obj_path.stem().string() + ".mtl"));
    fs::path mtl_path;
    for (const auto& c : candidates)
        if (std::error_code ignored; fs::is_regular_file(c, ignored)) {
            mtl_path = c;
            break;
        }
    if (mtl_path.empty()) {
        if (!mtllib.empty())
            log_warning("{}: material library '{}' not found; no albedo texture", obj_path.string(), mtllib);
        return {};
    }
    std::ifstream in(mtl_path);
    std::string line, texture;
    while (std::getline(in, line)) {
        LineParser parser(line, mtl_path.string(), 0);
        const std::string_view keyword = parser.next_token();
        if (keyword == "map_Kd") {
            // Options such as "-s 1 1 1" may precede the file name; the name is the last token.
            std::string_view rest = parser.rest_trimmed();
            const auto space = rest.find_last_of(" \t");
            texture = std::string(space == std::string_view::npos ? rest : rest.substr(space + 1));
        }
    }
    if (texture.empty()) return {};
    fs::path texture_path = mtl_path.parent_path() / texture;
    std::error_code status;  // a name the file system rejects (too long, ...) is a missing texture
    if (!fs::is_regular_file(texture_path, status)) {
        log_warning("{}: albedo texture '{}' not found", mtl_path.string(), texture_path.string());
        return {};
    }
    return texture_path.string();
}

}  // namespace

TriangleMesh load_obj(const std::string& path, const MeshLoadOptions& options) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw_error("cannot open '{}': {}", path, std::strerror(errno));
    TriangleMesh mesh;
    mesh.source_path = path;
    std::string mtllib;
    bool any_color = false, any_plain = false;
    std::vector<std::pair<int, int>> corners;  // (position, uv) of the current face
    // The current `o` / `g` / `usemtl` state. When a face follows a change, the group with the
    // same three names is looked up (files often come back to a material) or appended, so groups
    // are unique and those without faces are never recorded.
    FaceGroup current;
    bool group_changed = true;
    bool any_group_statement = false;
    int current_group = 0;
    std::string line;
    std::size_t line_number = 0;
    while (std::getline(in, line)) {
        ++line_number;
        LineParser parser(line, path, line_number);
        const std::string_view keyword = parser.next_token();
        if (keyword.empty() || keyword[0] == '#') continue;
        if (keyword == "v") {
            Vec3f p;
            for (int k = 0; k < 3; ++k) p[k] = parser.next_float("vertex");
            if (!parser.at_end()) {
                Vec3f c;
                c.x = parser.next_float("vertex colour");
                if (parser.at_end()) {
                    any_plain = true;  // "v x y z w": homogeneous weight, ignored
                } else {
                    c.y = parser.next_float("vertex colour");
                    c.z = parser.next_float("vertex colour");
                    mesh.colors.resize(mesh.positions.size(), Vec3f{1, 1, 1});
                    mesh.colors.push_back(c);
                    any_color = true;
                }
            } else {
                any_plain = true;
            }
            mesh.positions.push_back(p);
        } else if (keyword == "vt") {
            Vec2f t;
            t.x = parser.next_float("texture coordinate");
            t.y = parser.at_end() ? 0.0f : parser.next_float("texture coordinate");
            mesh.uvs.push_back(t);
        } else if (keyword == "f") {
            corners.clear();
            for (std::string_view token = parser.next_token(); !token.empty(); token = parser.next_token()) {
                const auto slash = token.find('/');
                const std::string_view vpart = token.substr(0, slash);
                int uv = -1;
                if (slash != std::string_view::npos) {
                    const std::string_view after = token.substr(slash + 1);
                    const std::string_view tpart = after.substr(0, after.find('/'));
                    if (!tpart.empty()) uv = resolve_index(tpart, mesh.uvs.size(), parser, "texture coordinate");
                }
                corners.emplace_back(resolve_index(vpart, mesh.positions.size(), parser, "vertex"), uv);
            }
            if (corners.size() < 3) parser.fail("face has {} corners, at least 3 needed", corners.size());
            const bool has_uv = corners[0].second >= 0;
            for (const auto& c : corners)
                if ((c.second >= 0) != has_uv) parser.fail("face mixes corners with and without texture coordinates");
            if (!mesh.triangles.empty() && has_uv != !mesh.uv_triangles.empty())
                parser.fail("some faces have texture coordinates and others do not");
            if (group_changed) {
                const auto same =
                    std::find_if(mesh.face_groups.begin(), mesh.face_groups.end(), [&](const FaceGroup& g) {
                        return g.object == current.object && g.group == current.group &&
                               g.material == current.material;
                    });
                current_group = int(same - mesh.face_groups.begin());
                if (same == mesh.face_groups.end()) mesh.face_groups.push_back(current);
                group_changed = false;
            }
            for (std::size_t k = 1; k + 1 < corners.size(); ++k) {
                mesh.face_group.push_back(current_group);
                mesh.triangles.push_back({corners[0].first, corners[k].first, corners[k + 1].first});
                if (has_uv) mesh.uv_triangles.push_back({corners[0].second, corners[k].second, corners[k + 1].second});
            }
        } else if (keyword == "mtllib") {
            mtllib = std::string(parser.rest_trimmed());
        } else if (keyword == "o" || keyword == "g" || keyword == "usemtl") {
            // "g a b" names several groups at once; the whole rest of the line is the key.
            const std::string name(parser.rest_trimmed());
            std::string& field = keyword == "o"   ? current.object
                                 : keyword == "g" ? current.group
                                                  : current.material;
            if (field != name) group_changed = true;
            field = name;
            any_group_statement = true;
        }
        // vn (normals are recomputed, spec 1.2), s, l, p: ignored.
    }
    if (in.bad()) throw_error("cannot read '{}': I/O error", path);
    // A file without o/g/usemtl has no structure: both vectors stay empty (one implicit group).
    if (!any_group_statement) {
        mesh.face_groups.clear();
        mesh.face_group.clear();
    }
    if (any_color && any_plain) mesh.colors.resize(mesh.positions.size(), Vec3f{1, 1, 1});
    if (!mesh.has_uvs()) mesh.uvs.clear();
    if (options.load_textures) {
        mesh.albedo_path = find_albedo_texture(fs::path(path), mtllib);
        if (!mesh.albedo_path.empty()) mesh.albedo = read_image(mesh.albedo_path);
    }
    finish_loaded_mesh(mesh, path, options);
    return mesh;
}

}  // namespace tdf
