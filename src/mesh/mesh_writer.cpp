// OBJ/MTL and GLB writers. The GLB is written by hand (a JSON chunk and a BIN chunk) rather
// than through tinygltf: the format is small, and this keeps the mesh module's dependencies as
// they are.
#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_writer.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
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

void check_face_materials(const FaceMaterials& parts, const TriangleMesh& mesh, const std::string& path) {
    if (parts.empty()) return;
    if (parts.face_material.size() != mesh.triangles.size())
        throw_error("{}: {} face materials for {} faces", path, parts.face_material.size(), mesh.triangles.size());
    for (const int m : parts.face_material)
        if (m < 0 || std::size_t(m) >= parts.names.size())
            throw_error("{}: face material {} is not one of the {} materials", path, m, parts.names.size());
}

}  // namespace

namespace {

// OBJ `o`/`g` lines for face f when its input group differs from face f - 1's (faces keep their
// order; a name may appear again further down, which OBJ allows).
void write_obj_group_lines(fmt::memory_buffer& out, const TriangleMesh& mesh, std::size_t f) {
    if (mesh.face_group.size() != mesh.triangles.size() || mesh.face_groups.empty()) return;
    const int g = mesh.face_group[f];
    if (f > 0 && mesh.face_group[f - 1] == g) return;
    if (g < 0 || std::size_t(g) >= mesh.face_groups.size()) return;
    const FaceGroup& group = mesh.face_groups[std::size_t(g)];
    const FaceGroup* previous =
        f > 0 && mesh.face_group[f - 1] >= 0 && std::size_t(mesh.face_group[f - 1]) < mesh.face_groups.size()
            ? &mesh.face_groups[std::size_t(mesh.face_group[f - 1])]
            : nullptr;
    // OBJ names end at whitespace: spaces inside glTF names become underscores.
    const auto name = [](std::string s) {
        for (char& c : s)
            if (std::isspace(static_cast<unsigned char>(c))) c = '_';
        return s;
    };
    if (!group.object.empty() && (!previous || previous->object != group.object))
        fmt::format_to(std::back_inserter(out), "o {}\n", name(group.object));
    if (!group.group.empty() &&
        (!previous || previous->group != group.group || previous->object != group.object))
        fmt::format_to(std::back_inserter(out), "g {}\n", name(group.group));
}

}  // namespace

void write_obj(const std::string& obj_path, const TriangleMesh& mesh, const ObjMaterial& material,
               const FaceMaterials& parts) {
    check_writable_mesh(mesh, obj_path);
    check_face_materials(parts, mesh, obj_path);
    const fs::path path(obj_path);
    const std::string mtl_name = path.stem().string() + ".mtl";
    const bool has_normals = mesh.normals.size() == mesh.positions.size();

    std::string mtl = "# written by tdf\n";
    for (const std::string& name : parts.empty() ? std::vector<std::string>{material.name} : parts.names) {
        mtl += fmt::format("newmtl {}\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nillum 1\n", name);
        if (!material.albedo_map.empty()) mtl += fmt::format("map_Kd {}\n", material.albedo_map);
        if (!material.normal_map.empty())
            mtl += fmt::format("norm {}\nmap_Bump -bm 1 {}\n", material.normal_map, material.normal_map);
        if (!material.height_map.empty())
            mtl += fmt::format("disp -mm {:.9g} {:.9g} {}\n", material.height_base, material.height_gain,
                               material.height_map);
    }
    write_text_atomically((path.parent_path() / mtl_name).string(), mtl);

    fmt::memory_buffer out;
    fmt::format_to(std::back_inserter(out),
                   "# written by tdf: {} vertices, {} faces\nmtllib {}\n",
                   mesh.positions.size(),
                   mesh.triangles.size(),
                   mtl_name);
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
    // One normal per position (the renderer's: area-weighted, compute_normals), so `vn` k pairs
    // with `v` k and other programs shade the smooth surface tdf shades.
    if (has_normals)
        for (const Vec3f& n : mesh.normals)
            fmt::format_to(std::back_inserter(out), "vn {:.7g} {:.7g} {:.7g}\n", n.x, n.y, n.z);
    if (parts.empty()) fmt::format_to(std::back_inserter(out), "usemtl {}\n", material.name);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        write_obj_group_lines(out, mesh, f);
        if (!parts.empty() && (f == 0 || parts.face_material[f] != parts.face_material[f - 1]))
            fmt::format_to(std::back_inserter(out), "usemtl {}\n", parts.names[std::size_t(parts.face_material[f])]);
        const Vec3i& t = mesh.triangles[f];
        const Vec3i u = mesh.has_uvs() ? mesh.uv_triangles[f] : Vec3i{0, 0, 0};
        out.push_back('f');
        for (int k = 0; k < 3; ++k) {
            if (mesh.has_uvs() && has_normals)
                fmt::format_to(std::back_inserter(out), " {}/{}/{}", t[k] + 1, u[k] + 1, t[k] + 1);
            else if (mesh.has_uvs())
                fmt::format_to(std::back_inserter(out), " {}/{}", t[k] + 1, u[k] + 1);
            else if (has_normals)
                fmt::format_to(std::back_inserter(out), " {}//{}", t[k] + 1, t[k] + 1);
            else
                fmt::format_to(std::back_inserter(out), " {}", t[k] + 1);
        }
        out.push_back('\n');
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

// world = A local + t, from glTF's column-major 4x4.
struct Affine {
    double a[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    double t[3] = {0, 0, 0};

    static Affine from_gltf(const std::array<double, 16>& m) {
        Affine x;
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) x.a[r][c] = m[std::size_t(4 * c + r)];
            x.t[r] = m[std::size_t(12 + r)];
        }
        return x;
    }
    double determinant() const {
        return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
               a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
               a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    }
    // Returns false for a singular matrix.
    bool inverse(Affine& out) const {
        const double d = determinant();
        if (!(std::abs(d) > 1e-300) || !std::isfinite(d)) return false;
        const double s = 1.0 / d;
        out.a[0][0] = (a[1][1] * a[2][2] - a[1][2] * a[2][1]) * s;
        out.a[0][1] = (a[0][2] * a[2][1] - a[0][1] * a[2][2]) * s;
        out.a[0][2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) * s;
        out.a[1][0] = (a[1][2] * a[2][0] - a[1][0] * a[2][2]) * s;
        out.a[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) * s;
        out.a[1][2] = (a[0][2] * a[1][0] - a[0][0] * a[1][2]) * s;
        out.a[2][0] = (a[1][0] * a[2][1] - a[1][1] * a[2][0]) * s;
        out.a[2][1] = (a[0][1] * a[2][0] - a[0][0] * a[2][1]) * s;
        out.a[2][2] = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) * s;
        for (int r = 0; r < 3; ++r)
            out.t[r] = -(out.a[r][0] * t[0] + out.a[r][1] * t[1] + out.a[r][2] * t[2]);
        return true;
    }
    Vec3f point(Vec3f p) const {
        Vec3f q;
        for (int r = 0; r < 3; ++r) q[r] = float(a[r][0] * p.x + a[r][1] * p.y + a[r][2] * p.z + t[r]);
        return q;
    }
    Vec3f direction(Vec3f v) const {
        Vec3f q;
        for (int r = 0; r < 3; ++r) q[r] = float(a[r][0] * v.x + a[r][1] * v.y + a[r][2] * v.z);
        return q;
    }
    Vec3f transposed_direction(Vec3f v) const {
        Vec3f q;
        for (int c = 0; c < 3; ++c) q[c] = float(a[0][c] * v.x + a[1][c] * v.y + a[2][c] * v.z);
        return q;
    }
};

bool is_identity(const std::array<double, 16>& m) {
    for (int i = 0; i < 16; ++i)
        if (m[std::size_t(i)] != ((i % 5 == 0) ? 1.0 : 0.0)) return false;
    return true;
}

// One glTF node (with its own mesh) of the output and the faces of each of its primitives.
struct OutputNode {
    std::string name, mesh_name;
    std::array<double, 16> world_from_node{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::vector<std::vector<std::size_t>> primitives;
    std::vector<int> materials;  ///< per primitive
};

// The input's structure (TriangleMesh::face_groups): a glTF input gives one node per input node
// and one primitive per input primitive; an OBJ input one node per (object, group) and one
// primitive per material. Without groups: one node, one primitive. Order of first appearance.
// With `parts`, a primitive holds one part's faces (its material in OutputNode::materials).
std::vector<OutputNode> split_into_nodes(const TriangleMesh& mesh, const FaceMaterials& parts) {
    const bool grouped = !mesh.face_groups.empty() && mesh.face_group.size() == mesh.triangles.size();
    std::vector<OutputNode> nodes;
    std::map<std::tuple<int, std::string, std::string>, std::size_t> node_of;
    std::map<std::pair<std::size_t, std::tuple<int, int, std::string, int>>, std::size_t> primitive_of;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const int gi = grouped ? mesh.face_group[f] : -1;
        static const FaceGroup kNone;
        const FaceGroup& g =
            gi >= 0 && std::size_t(gi) < mesh.face_groups.size() ? mesh.face_groups[std::size_t(gi)] : kNone;
        const bool gltf = g.gltf_node >= 0;
        const auto node_key = gltf ? std::make_tuple(g.gltf_node, std::string(), std::string())
                                   : std::make_tuple(-1, g.object, g.group);
        const auto [node_it, new_node] = node_of.emplace(node_key, nodes.size());
        if (new_node) {
            OutputNode node;
            node.name = g.object.empty() ? g.group : g.object;
            node.mesh_name = g.group.empty() ? g.object : g.group;
            if (gltf) node.world_from_node = g.world_from_node;
            nodes.push_back(std::move(node));
        }
        OutputNode& node = nodes[node_it->second];
        const int part = parts.empty() ? 0 : parts.face_material[f];
        const auto primitive_key = gltf ? std::make_tuple(g.gltf_mesh, g.gltf_primitive, std::string(), part)
                                        : std::make_tuple(-1, -1, g.material, part);
        const auto [prim_it, new_primitive] =
            primitive_of.emplace(std::make_pair(node_it->second, primitive_key), node.primitives.size());
        if (new_primitive) {
            node.primitives.emplace_back();
            node.materials.push_back(part);
        }
        node.primitives[prim_it->second].push_back(f);
    }
    return nodes;
}

// One primitive's vertex arrays in the node's own coordinates.
struct GlbPrimitive {
    std::vector<std::uint32_t> indices;
    std::vector<float> positions, normals, tangents, texcoords, colors;
    Vec3f lower{0, 0, 0}, upper{0, 0, 0};  // the positions' bounds (glTF requires them)
};

// Which vertex attributes the file carries.
struct GlbAttributes {
    bool normals = false, tangents = false, colors = false;
};

GlbPrimitive gather_primitive(const TriangleMesh& mesh, const std::vector<std::size_t>& faces, bool mirrored,
                              const Affine& world_from_node, const Affine& node_from_world,
                              const GlbAttributes& attributes) {
    // One glTF vertex per distinct (position, uv, tangent) corner.
    std::map<std::tuple<int, int, int>, std::uint32_t> vertex_ids;
    GlbPrimitive out;
    out.indices.reserve(faces.size() * 3);
    for (const std::size_t f : faces)
        for (int j = 0; j < 3; ++j) {
            const int k = mirrored && j > 0 ? 3 - j : j;
            const int p = mesh.triangles[f][k];
            const int t = mesh.has_uvs() ? mesh.uv_triangles[f][k] : -1;
            const int g = attributes.tangents ? mesh.tangent_triangles[f][k] : -1;
            const auto [it, inserted] =
                vertex_ids.emplace(std::make_tuple(p, t, g), std::uint32_t(vertex_ids.size()));
            out.indices.push_back(it->second);
            if (!inserted) continue;
            const Vec3f position = node_from_world.point(mesh.positions[std::size_t(p)]);
            out.lower = it->second == 0 ? position : min(out.lower, position);
            out.upper = it->second == 0 ? position : max(out.upper, position);
            out.positions.insert(out.positions.end(), {position.x, position.y, position.z});
            if (attributes.normals) {
                // Normals transform by the inverse transpose: n_node ~ A^T n_world.
                const Vec3f n = normalize_or_zero(
                    world_from_node.transposed_direction(mesh.normals[std::size_t(p)]));
                out.normals.insert(out.normals.end(), {n.x, n.y, n.z});
            }
            if (attributes.tangents) {
                const Vec4f tg = mesh.tangents[std::size_t(g)];
                const Vec3f d = normalize_or_zero(node_from_world.direction({tg.x, tg.y, tg.z}));
                // Our handedness is +1 when N x T points toward increasing OBJ v, i.e. toward
                // decreasing glTF v, which is exactly glTF's bitangent = cross(N, T) * w.
                // Viewers form that cross product from the transformed N and T, so w stays.
                out.tangents.insert(out.tangents.end(), {d.x, d.y, d.z, tg.w >= 0.0f ? 1.0f : -1.0f});
            }
            if (t >= 0) {
                const Vec2f uv = mesh.uvs[std::size_t(t)];
                out.texcoords.insert(out.texcoords.end(), {uv.x, 1.0f - uv.y});  // glTF v points down
            }
            if (attributes.colors) {
                const Vec3f c = mesh.colors[std::size_t(p)];
                out.colors.insert(out.colors.end(), {c.x, c.y, c.z});
            }
        }
    TDF_CHECK_EQ(out.positions.size(), vertex_ids.size() * 3);
    return out;
}

// The GLB container: a 12-byte header, the JSON chunk (padded with spaces to 4 bytes), the BIN chunk.
void write_glb_container(const std::string& path, std::string json, const std::vector<std::uint8_t>& data) {
    while (json.size() % 4 != 0) json.push_back(' ');
    write_atomically(path, [&](const std::string& temporary) {
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

}  // namespace

std::string encode_png_bytes(const Image& image, Quantize quantize) {
    // Through write_png (the one PNG encoder) and a temporary file, so the bytes are exactly those
    // of a PNG file written with the same settings.
    const fs::path folder = fs::temp_directory_path();
    std::string temporary;
    for (int attempt = 0;; ++attempt) {
        temporary =
            (folder /
             fmt::format("tdf_png_{}_{}_{}.png", ::getpid(), static_cast<const void*>(&image), attempt))
                .string();
        if (!fs::exists(temporary)) break;
    }
    write_png(temporary, image, 8, quantize);
    std::string bytes = read_text_file(temporary);
    std::error_code ignored;
    fs::remove(temporary, ignored);
    return bytes;
}

void write_glb(const std::string& path, const TriangleMesh& mesh, const Image* albedo,
               const Image* normal_map, Quantize quantize) {
    GlbMaps maps;
    if (albedo && !albedo->empty()) maps.albedo_png = encode_png_bytes(*albedo, quantize);
    if (normal_map && !normal_map->empty()) maps.normal_png = encode_png_bytes(*normal_map, quantize);
    write_glb(path, mesh, maps);
}

namespace {

// The glTF material: dielectric and fully rough (the closest glTF's PBR model comes to tdf's
// Lambertian shading), the maps' PNGs through `add_image` (which embeds them and returns the image
// index), the height map and its scale under extras; multi-part, the same material under each
// part's name (the textures are one shared atlas).
Json glb_materials(const GlbMaps& maps, const FaceMaterials& parts, Json& textures,
                   const std::function<std::size_t(const std::string& png, const char* name)>& add_image) {
    Json pbr = {{"metallicFactor", 0.0}, {"roughnessFactor", 1.0}};
    Json material = {{"name", "material"}};
    for (const auto& [png, slot] : {std::make_pair(&maps.albedo_png, "baseColorTexture"),
                                    std::make_pair(&maps.normal_png, "normalTexture"),
                                    std::make_pair(&maps.occlusion_png, "occlusionTexture")}) {
        if (png->empty()) continue;
        textures.push_back({{"source", add_image(*png, nullptr)}, {"sampler", 0}});
        const Json info = {{"index", textures.size() - 1}};
        if (std::string(slot) == "baseColorTexture")
            pbr[slot] = info;
        else
            material[slot] = info;
    }
    material["pbrMetallicRoughness"] = pbr;
    if (!maps.height_png.empty()) {
        Json extras = maps.height_extras;
        extras["image"] = add_image(maps.height_png, "tdf_height");
        material["extras"] = {{"tdf_height", extras}};
    }
    Json materials = Json::array({material});
    if (!parts.empty()) {
        materials = Json::array();
        for (const std::string& name : parts.names) {
            material["name"] = name;
            materials.push_back(material);
        }
    }
    return materials;
}

}  // namespace

void write_glb(const std::string& path, const TriangleMesh& mesh, const GlbMaps& maps, const FaceMaterials& parts) {
    check_writable_mesh(mesh, path);
    check_face_materials(parts, mesh, path);
    const bool has_tangents =
        mesh.tangent_triangles.size() == mesh.triangles.size() && !mesh.tangents.empty();
    const bool has_normals = mesh.normals.size() == mesh.positions.size();
    // glTF multiplies COLOR_0 into baseColorTexture; tdf renders the texture alone when a mesh has
    // both (and a baked albedo already holds the colours), so the colours go only without one.
    const bool write_colors = mesh.has_colors() && maps.albedo_png.empty();
    const GlbAttributes glb_attributes{has_normals, has_tangents, write_colors};

    BinaryBuffer bin;
    Json views = Json::array(), accessors = Json::array();
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

    Json nodes = Json::array(), meshes = Json::array(), scene_nodes = Json::array();
    for (const OutputNode& node : split_into_nodes(mesh, parts)) {
        // Positions were loaded in world coordinates (the loader applied the node's matrix): write
        // them back in the node's own coordinates under the same matrix.
        Affine node_from_world;
        const Affine world_from_node = Affine::from_gltf(node.world_from_node);
        if (!world_from_node.inverse(node_from_world))
            throw_error("{}: node '{}' has a singular matrix; cannot write its mesh in node coordinates",
                        path,
                        node.name);
        // The loader reversed the winding under a mirroring matrix (counter-clockwise = front in
        // world); glTF's viewers reverse it again for such nodes, so the file keeps the input's order.
        const bool mirrored = world_from_node.determinant() < 0;
        Json primitives = Json::array();
        for (std::size_t primitive = 0; primitive < node.primitives.size(); ++primitive) {
            const std::vector<std::size_t>& faces = node.primitives[primitive];
            const GlbPrimitive prim =
                gather_primitive(mesh, faces, mirrored, world_from_node, node_from_world, glb_attributes);
            const std::vector<std::uint32_t>& indices = prim.indices;
            const Vec3f lower = prim.lower, upper = prim.upper;
            Json attributes = Json::object();
            const std::size_t index_view = add_view(bin.append(indices), indices.size() * 4, 34963);
            accessors.push_back({{"bufferView", index_view},
                                 {"componentType", 5125},
                                 {"count", indices.size()},
                                 {"type", "SCALAR"}});
            const std::size_t index_accessor = accessors.size() - 1;
            attributes["POSITION"] = add_floats(prim.positions, "VEC3", 3);
            accessors[attributes["POSITION"].get<std::size_t>()]["min"] = {lower.x, lower.y, lower.z};
            accessors[attributes["POSITION"].get<std::size_t>()]["max"] = {upper.x, upper.y, upper.z};
            if (has_normals) attributes["NORMAL"] = add_floats(prim.normals, "VEC3", 3);
            if (has_tangents) attributes["TANGENT"] = add_floats(prim.tangents, "VEC4", 4);
            if (!prim.texcoords.empty()) attributes["TEXCOORD_0"] = add_floats(prim.texcoords, "VEC2", 2);
            if (!prim.colors.empty()) attributes["COLOR_0"] = add_floats(prim.colors, "VEC3", 3);
            primitives.push_back(
                {{"attributes", attributes}, {"indices", index_accessor}, {"material", node.materials[primitive]}, {"mode", 4}});
        }
        Json mesh_json = {{"primitives", primitives}};
        if (!node.mesh_name.empty()) mesh_json["name"] = node.mesh_name;
        meshes.push_back(mesh_json);
        Json node_json = {{"mesh", meshes.size() - 1}};
        if (!node.name.empty()) node_json["name"] = node.name;
        if (!is_identity(node.world_from_node)) node_json["matrix"] = node.world_from_node;
        scene_nodes.push_back(nodes.size());
        nodes.push_back(node_json);
    }

    Json images = Json::array(), textures = Json::array();
    const auto add_image = [&](const std::string& png, const char* name) {
        const std::size_t view = add_view(bin.append_bytes(png.data(), png.size()), png.size(), 0);
        Json image = {{"bufferView", view}, {"mimeType", "image/png"}};
        if (name) image["name"] = name;
        images.push_back(image);
        return images.size() - 1;
    };
    const Json materials = glb_materials(maps, parts, textures, add_image);
    Json gltf = {{"asset", {{"version", "2.0"}, {"generator", "tdf"}}},
                 {"scene", 0},
                 {"scenes", Json::array({{{"nodes", scene_nodes}}})},
                 {"nodes", nodes},
                 {"meshes", meshes},
                 {"materials", materials},
                 {"accessors", accessors},
                 {"bufferViews", views},
                 {"buffers", Json::array({{{"byteLength", bin.bytes().size()}}})}};
    if (!images.empty()) gltf["images"] = images;
    if (!textures.empty()) {
        gltf["textures"] = textures;
        gltf["samplers"] = Json::array({{{"magFilter", 9729}, {"minFilter", 9987}}});
    }
    std::string json = gltf.dump();
    write_glb_container(path, std::move(json), bin.bytes());
}

}  // namespace tdf
