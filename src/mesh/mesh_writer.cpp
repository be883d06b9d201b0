// OBJ/MTL and GLB writers. The GLB is written by hand (a JSON chunk and a BIN chunk) rather
// than through tinygltf: the format is small, and this keeps the mesh module's dependencies as
// they are.
#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_writer.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <tuple>

namespace tdf {

namespace fs = std::filesystem;

namespace {

void check_writable_mesh(const TriangleMesh& mesh, const std::string& path) {
    if (mesh.triangles.empty()) throw_error("{}: refusing to write a mesh without faces", path);
    if (mesh.has_uvs() && mesh.uv_triangles.size() != mesh.triangles.size())
        throw_error("{}: {} UV faces for {} faces", path, mesh.uv_triangles.size(), mesh.triangles.size());
    if (mesh.has_colors() && mesh.colors.size() != mesh.positions.size())
        throw_error("{}: {} vertex colours for {} vertices", path, mesh.colors.size(), mesh.positions.size());
}

}  // namespace

void write_obj(const std::string& obj_path, const TriangleMesh& mesh, const ObjMaterial& material) {
    check_writable_mesh(mesh, obj_path);
    const fs::path path(obj_path);
    const std::string mtl_name = path.stem().string() + ".mtl";

    std::string mtl =
        fmt::format("# written by tdf\nnewmtl {}\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nillum 1\n", material.name);
    if (!material.albedo_map.empty()) mtl += fmt::format("map_Kd {}\n", material.albedo_map);
    if (!material.normal_map.empty())
        mtl += fmt::format("norm {}\nmap_Bump -bm 1 {}\n", material.normal_map, material.normal_map);
    write_text_atomically((path.parent_path() / mtl_name).string(), mtl);

    fmt::memory_buffer out;
    fmt::format_to(std::back_inserter(out),
                   "# written by tdf: {} vertices, {} faces\nmtllib {}\nusemtl {}\n",
                   mesh.positions.size(),
                   mesh.triangles.size(),
                   mtl_name,
                   material.name);
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        const Vec3f p = mesh.positions[i];
        if (mesh.has_colors()) {
            const Vec3f c = mesh.colors[i];
            fmt::format_to(std::back_inserter(out),
                           "v {:.9g} {:.9g} {:.9g} {:.6g} {:.6g} {:.6g}\n",
                           p.x,
                           p.y,
                           p.z,
                           c.x,
                           c.y,
                           c.z);
        } else {
            fmt::format_to(std::back_inserter(out), "v {:.9g} {:.9g} {:.9g}\n", p.x, p.y, p.z);
        }
    }
    if (mesh.has_uvs())
        for (const Vec2f& t : mesh.uvs)
            fmt::format_to(std::back_inserter(out), "vt {:.9g} {:.9g}\n", t.x, t.y);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Vec3i& t = mesh.triangles[f];
        if (mesh.has_uvs()) {
            const Vec3i& u = mesh.uv_triangles[f];
            fmt::format_to(std::back_inserter(out),
                           "f {}/{} {}/{} {}/{}\n",
                           t.x + 1,
                           u.x + 1,
                           t.y + 1,
                           u.y + 1,
                           t.z + 1,
                           u.z + 1);
        } else {
            fmt::format_to(std::back_inserter(out), "f {} {} {}\n", t.x + 1, t.y + 1, t.z + 1);
        }
    }
    write_text_atomically(obj_path, fmt::to_string(out));
}

namespace {

// Appends raw bytes to the BIN chunk, 4-byte aligned as glTF requires for accessors.
class BinaryBuffer {
public:
    template <typename T>
    std::size_t append(const std::vector<T>& values) {
        return append_bytes(values.data(), values.size() * sizeof(T));
    }
    std::size_t append_bytes(const void* data, std::size_t size) {
        const std::size_t offset = m_bytes.size();
        const auto* p = static_cast<const std::uint8_t*>(data);
        m_bytes.insert(m_bytes.end(), p, p + size);
        while (m_bytes.size() % 4 != 0) m_bytes.push_back(0);
        return offset;
    }
    const std::vector<std::uint8_t>& bytes() const { return m_bytes; }

private:
    std::vector<std::uint8_t> m_bytes;
};

// The PNG file bytes of `image` (8-bit, rounded), via a temporary file next to `near_path`.
std::string encode_png(const Image& image, const std::string& near_path) {
    const std::string temporary = near_path + ".texture.png";
    write_png(temporary, image, 8, Quantize::Round);
    std::string bytes = read_text_file(temporary);
    std::error_code ignored;
    fs::remove(temporary, ignored);
    return bytes;
}

}  // namespace

void write_glb(const std::string& path, const TriangleMesh& mesh, const Image* albedo,
               const Image* normal_map) {
    check_writable_mesh(mesh, path);
    const bool has_tangents =
        mesh.tangent_triangles.size() == mesh.triangles.size() && !mesh.tangents.empty();
    const bool has_normals = mesh.normals.size() == mesh.positions.size();

    // One glTF vertex per distinct (position, uv, tangent) corner.
    std::map<std::tuple<int, int, int>, std::uint32_t> vertex_ids;
    std::vector<std::uint32_t> indices;
    std::vector<float> positions, normals, tangents, texcoords, colors;
    Vec3f lower = mesh.positions[std::size_t(mesh.triangles[0].x)], upper = lower;
    indices.reserve(mesh.triangles.size() * 3);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            const int p = mesh.triangles[f][k];
            const int t = mesh.has_uvs() ? mesh.uv_triangles[f][k] : -1;
            const int g = has_tangents ? mesh.tangent_triangles[f][k] : -1;
            const auto [it, inserted] =
                vertex_ids.emplace(std::make_tuple(p, t, g), std::uint32_t(vertex_ids.size()));
            indices.push_back(it->second);
            if (!inserted) continue;
            const Vec3f position = mesh.positions[std::size_t(p)];
            lower = min(lower, position);
            upper = max(upper, position);
            positions.insert(positions.end(), {position.x, position.y, position.z});
            if (has_normals) {
                const Vec3f n = mesh.normals[std::size_t(p)];
                normals.insert(normals.end(), {n.x, n.y, n.z});
            }
            if (has_tangents) {
                const Vec4f tg = mesh.tangents[std::size_t(g)];
                // Our handedness is +1 when N x T points toward increasing OBJ v, i.e. toward
                // decreasing glTF v, which is exactly glTF's bitangent = cross(N, T) * w.
                tangents.insert(tangents.end(), {tg.x, tg.y, tg.z, tg.w >= 0.0f ? 1.0f : -1.0f});
            }
            if (t >= 0) {
                const Vec2f uv = mesh.uvs[std::size_t(t)];
                texcoords.insert(texcoords.end(), {uv.x, 1.0f - uv.y});  // glTF v points down
            }
            if (mesh.has_colors()) {
                const Vec3f c = mesh.colors[std::size_t(p)];
                colors.insert(colors.end(), {c.x, c.y, c.z});
            }
        }
    const std::size_t vertex_count = vertex_ids.size();

    using Json = nlohmann::json;
    BinaryBuffer bin;
    Json views = Json::array(), accessors = Json::array(), attributes = Json::object();
    const auto add_view = [&](std::size_t offset, std::size_t length, int target) {
        Json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}};
        if (target != 0) view["target"] = target;
        views.push_back(view);
        return views.size() - 1;
    };
    const auto add_floats = [&](const std::vector<float>& values, const char* type, int components) {
        const std::size_t view = add_view(bin.append(values), values.size() * sizeof(float), 34962);
        accessors.push_back({{"bufferView", view},
                             {"componentType", 5126},
                             {"count", values.size() / std::size_t(components)},
                             {"type", type}});
        return accessors.size() - 1;
    };
    const std::size_t index_view = add_view(bin.append(indices), indices.size() * 4, 34963);
    accessors.push_back(
        {{"bufferView", index_view}, {"componentType", 5125}, {"count", indices.size()}, {"type", "SCALAR"}});
    attributes["POSITION"] = add_floats(positions, "VEC3", 3);
    accessors[attributes["POSITION"].get<std::size_t>()]["min"] = {lower.x, lower.y, lower.z};
    accessors[attributes["POSITION"].get<std::size_t>()]["max"] = {upper.x, upper.y, upper.z};
    if (has_normals) attributes["NORMAL"] = add_floats(normals, "VEC3", 3);
    if (has_tangents) attributes["TANGENT"] = add_floats(tangents, "VEC4", 4);
    if (!texcoords.empty()) attributes["TEXCOORD_0"] = add_floats(texcoords, "VEC2", 2);
    if (!colors.empty()) attributes["COLOR_0"] = add_floats(colors, "VEC3", 3);
    TDF_CHECK_EQ(positions.size(), vertex_count * 3);

    Json images = Json::array(), textures = Json::array();
    Json pbr = {{"metallicFactor", 0.0}, {"roughnessFactor", 0.5}};
    Json material = {{"name", "material"}};
    std::vector<std::pair<const Image*, const char*>> maps;
    if (albedo && !albedo->empty()) maps.emplace_back(albedo, "baseColorTexture");
    if (normal_map && !normal_map->empty()) maps.emplace_back(normal_map, "normalTexture");

    write_atomically(path, [&](const std::string& temporary) {
        for (const auto& [image, slot] : maps) {
            const std::string png = encode_png(*image, temporary);
            const std::size_t view = add_view(bin.append_bytes(png.data(), png.size()), png.size(), 0);
            images.push_back({{"bufferView", view}, {"mimeType", "image/png"}});
            textures.push_back({{"source", images.size() - 1}});
            const Json info = {{"index", textures.size() - 1}};
            if (std::string(slot) == "baseColorTexture")
                pbr[slot] = info;
            else
                material[slot] = info;
        }
        material["pbrMetallicRoughness"] = pbr;
        Json gltf = {
            {"asset", {{"version", "2.0"}, {"generator", "tdf"}}},
            {"scene", 0},
            {"scenes", Json::array({{{"nodes", {0}}}})},
            {"nodes", Json::array({{{"mesh", 0}}})},
            {"meshes",
             Json::array(
                 {{{"primitives",
                    Json::array(
                        {{{"attributes", attributes}, {"indices", 0}, {"material", 0}, {"mode", 4}}})}}})},
            {"materials", Json::array({material})},
            {"accessors", accessors},
            {"bufferViews", views},
            {"buffers", Json::array({{{"byteLength", bin.bytes().size()}}})}};
        if (!images.empty()) {
            gltf["images"] = images;
            gltf["textures"] = textures;
            gltf["samplers"] = Json::array({{{"magFilter", 9729}, {"minFilter", 9987}}});
            for (Json& t : gltf["textures"]) t["sampler"] = 0;
        }
        std::string json = gltf.dump();
        while (json.size() % 4 != 0) json.push_back(' ');
        const std::vector<std::uint8_t>& data = bin.bytes();
        const auto u32 = [](std::size_t v) { return std::uint32_t(v); };
        const std::uint32_t header[3] = {0x46546C67u, 2u, u32(12 + 8 + json.size() + 8 + data.size())};
        const std::uint32_t json_chunk[2] = {u32(json.size()), 0x4E4F534Au};
        const std::uint32_t bin_chunk[2] = {u32(data.size()), 0x004E4942u};
        std::ofstream out(temporary, std::ios::binary);
        if (!out) throw_error("cannot open '{}' for writing: {}", path, std::strerror(errno));
        out.write(reinterpret_cast<const char*>(header), sizeof(header));
        out.write(reinterpret_cast<const char*>(json_chunk), sizeof(json_chunk));
        out.write(json.data(), std::streamsize(json.size()));
        out.write(reinterpret_cast<const char*>(bin_chunk), sizeof(bin_chunk));
        out.write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
        out.flush();
        if (!out) throw_error("cannot write '{}': {} (disk full?)", path, std::strerror(errno));
    });
}

}  // namespace tdf
