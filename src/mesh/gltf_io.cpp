// glTF 2.0 (.gltf + .bin, .glb) through tinygltf (Debian's shared library, so no
// TINYGLTF_IMPLEMENTATION here). Geometry of every triangle primitive reachable from the
// default scene, with node transforms applied; TEXCOORD_0, COLOR_0 and the base colour texture.
//
// glTF splits vertices at UV seams; OBJ (and the reference, spec 1.2) shares one position
// between charts. Vertices with bit-identical transformed positions are therefore welded into
// one position index (UVs keep their own index buffer), so area-weighted normals stay smooth
// across seams exactly as for the equivalent OBJ.
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <unordered_map>

namespace tdf {

namespace fs = std::filesystem;

namespace {

using Mat4d = std::array<double, 16>;  // column-major, as glTF stores matrices

Mat4d identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }

Mat4d multiply(const Mat4d& a, const Mat4d& b) {
    Mat4d r{};
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row)
            for (int k = 0; k < 4; ++k) r[std::size_t(c * 4 + row)] += a[std::size_t(k * 4 + row)] * b[std::size_t(c * 4 + k)];
    return r;
}

Mat4d node_matrix(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        Mat4d m;
        std::copy(node.matrix.begin(), node.matrix.end(), m.begin());
        return m;
    }
    // T * R * S.
    Mat4d t = identity(), r = identity(), s = identity();
    if (node.translation.size() == 3)
        for (int i = 0; i < 3; ++i) t[std::size_t(12 + i)] = node.translation[std::size_t(i)];
    if (node.scale.size() == 3)
        for (int i = 0; i < 3; ++i) s[std::size_t(i * 5)] = node.scale[std::size_t(i)];
    if (node.rotation.size() == 4) {
        const double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2], w = node.rotation[3];
        r = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),     0,
             2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),     0,
             2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y), 0,
             0,                       0,                       0,                       1};
    }
    return multiply(t, multiply(r, s));
}

double determinant3(const Mat4d& m) {
    return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
           m[8] * (m[1] * m[6] - m[5] * m[2]);
}

const char* component_type_name(int type) {
    switch (type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
            return "BYTE";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return "UNSIGNED_BYTE";
        case TINYGLTF_COMPONENT_TYPE_SHORT:
            return "SHORT";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return "UNSIGNED_SHORT";
        case TINYGLTF_COMPONENT_TYPE_INT:
            return "INT";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
            return "UNSIGNED_INT";
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return "FLOAT";
        case TINYGLTF_COMPONENT_TYPE_DOUBLE:
            return "DOUBLE";
        default:
            return "unknown";
    }
}

class GltfReader {
public:
    GltfReader(const tinygltf::Model& model, const std::string& path) : m_model(model), m_path(path) {}

    // Reads `accessor` as `count` x `components` floats. Integer components are normalised
    // when the accessor says so (TEXCOORD / COLOR); index accessors use read_indices.
    std::vector<float> read_floats(int accessor_index, int components, const char* what) const {
        const tinygltf::Accessor& a = accessor(accessor_index, what);
        const int have = tinygltf::GetNumComponentsInType(std::uint32_t(a.type));
        if (have < components || have > 4)
            throw_error("{}: {} has {} components per element, expected {}", m_path, what, have, components);
        // glTF 2.0 (3.7.2.1): POSITION is FLOAT; TEXCOORD_n and COLOR_n are FLOAT or normalized
        // UNSIGNED_BYTE / UNSIGNED_SHORT. Anything else is a broken or quantized file we would
        // otherwise read as wrong numbers.
        const bool is_float = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
        const bool normalized_integer =
            a.normalized && (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                             a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
        if (!is_float && (std::strcmp(what, "POSITION") == 0 || !normalized_integer))
            throw_error(
                "{}: {} has component type {}{}, expected FLOAT{}",
                m_path,
                what,
                component_type_name(a.componentType),
                a.normalized ? " (normalized)" : "",
                std::strcmp(what, "POSITION") == 0 ? "" : " or normalized UNSIGNED_BYTE/UNSIGNED_SHORT");
        const unsigned char* base = nullptr;
        std::size_t stride = 0;
        data(a, what, base, stride);  // bounds-checks the count against the buffer before allocating
        std::vector<float> out(a.count * std::size_t(components));
        for (std::size_t i = 0; i < a.count; ++i)
            for (int c = 0; c < components; ++c) {
                const unsigned char* p = base + i * stride + std::size_t(c) * component_size(a);
                float v = 0;
                switch (a.componentType) {
                    case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&v, p, 4); break;
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = float(*p) / (a.normalized ? 255.f : 1.f); break;
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                        std::uint16_t u;
                        std::memcpy(&u, p, 2);
                        v = float(u) / (a.normalized ? 65535.f : 1.f);
                        break;
                    }
                    default:
                        throw_error("{}: {} has unsupported component type {}", m_path, what, a.componentType);
                }
                if (!std::isfinite(v)) throw_error("{}: {} has a non-finite value (element {})", m_path, what, i);
                out[i * std::size_t(components) + std::size_t(c)] = v;
            }
        return out;
    }

    std::vector<std::uint32_t> read_indices(int accessor_index) const {
        const tinygltf::Accessor& a = accessor(accessor_index, "indices");
        const unsigned char* base = nullptr;
        std::size_t stride = 0;
        data(a, "indices", base, stride);
        std::vector<std::uint32_t> out(a.count);
        for (std::size_t i = 0; i < a.count; ++i) {
            const unsigned char* p = base + i * stride;
            switch (a.componentType) {
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: out[i] = *p; break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                    std::uint16_t u;
                    std::memcpy(&u, p, 2);
                    out[i] = u;
                    break;
                }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: std::memcpy(&out[i], p, 4); break;
                default: throw_error("{}: indices have unsupported component type {}", m_path, a.componentType);
            }
        }
        return out;
    }

    std::size_t count(int accessor_index, const char* what) const { return accessor(accessor_index, what).count; }

private:
    const tinygltf::Accessor& accessor(int index, const char* what) const {
        if (index < 0 || std::size_t(index) >= m_model.accessors.size())
            throw_error("{}: {} names accessor {}, which does not exist", m_path, what, index);
        const tinygltf::Accessor& a = m_model.accessors[std::size_t(index)];
        if (a.sparse.isSparse) throw_error("{}: {} uses a sparse accessor (not supported)", m_path, what);
        return a;
    }

    static std::size_t component_size(const tinygltf::Accessor& a) {
        const int size = tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType));
        return size > 0 ? std::size_t(size) : 0;
    }

    // Start and stride of the accessor's elements, bounds-checked against the buffer.
    void data(const tinygltf::Accessor& a, const char* what, const unsigned char*& base, std::size_t& stride) const {
        if (a.bufferView < 0 || std::size_t(a.bufferView) >= m_model.bufferViews.size())
            throw_error("{}: {} has no valid buffer view", m_path, what);
        const tinygltf::BufferView& view = m_model.bufferViews[std::size_t(a.bufferView)];
        if (view.buffer < 0 || std::size_t(view.buffer) >= m_model.buffers.size())
            throw_error("{}: {} has no valid buffer", m_path, what);
        const std::vector<unsigned char>& buffer = m_model.buffers[std::size_t(view.buffer)].data;
        const int element = tinygltf::GetNumComponentsInType(std::uint32_t(a.type)) *
                            tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType));
        if (element <= 0) throw_error("{}: {} has an invalid type", m_path, what);
        stride = view.byteStride ? view.byteStride : std::size_t(element);
        // In 64-bit arithmetic that cannot wrap: every term is bounded by the buffer size first.
        const std::size_t size = buffer.size();
        if (view.byteOffset > size || a.byteOffset > size || view.byteLength > size || stride > size)
            throw_error("{}: {} reads past the end of its buffer (truncated file?)", m_path, what);
        const std::size_t start = view.byteOffset + a.byteOffset;
        if (a.count > 0 && (a.count - 1 > size / std::max<std::size_t>(stride, 1) ||
                            start + (a.count - 1) * stride + std::size_t(element) > size))
            throw_error("{}: {} has {} elements, more than its buffer holds (truncated file?)",
                        m_path,
                        what,
                        a.count);
        const std::size_t end = a.count == 0 ? start : start + (a.count - 1) * stride + std::size_t(element);
        if (end > buffer.size() || end > view.byteOffset + view.byteLength)
            throw_error("{}: {} reads past the end of its buffer (truncated file?)", m_path, what);
        base = buffer.data() + start;
    }

    const tinygltf::Model& m_model;
    std::string m_path;
};

// Keeps the encoded bytes instead of decoding every image (normal and roughness maps are
// 2048^2 in typical files); only the base colour texture is decoded, after parsing.
// tinygltf 2.7 passes a bufferView image's bytes without checking the view against its buffer
// (found by fuzzing: a heap overflow on a .glb whose view runs past the BIN chunk), so those
// bytes are not touched here; embedded_image_bytes() copies them with bounds checks instead.
bool keep_encoded_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                        const unsigned char* bytes, int size, void*) {
    if (image->bufferView < 0 && size > 0) image->image.assign(bytes, bytes + size);
    image->width = image->height = -1;
    return true;
}

// The bytes of an image stored in a buffer view, bounds-checked.
void embedded_image_bytes(const tinygltf::Model& model, int view_index, const std::string& path,
                          const unsigned char*& base, std::size_t& length) {
    if (view_index < 0 || std::size_t(view_index) >= model.bufferViews.size())
        throw_error("{}: image buffer view {} does not exist", path, view_index);
    const tinygltf::BufferView& view = model.bufferViews[std::size_t(view_index)];
    if (view.buffer < 0 || std::size_t(view.buffer) >= model.buffers.size())
        throw_error("{}: image buffer view {} has no valid buffer", path, view_index);
    const std::vector<unsigned char>& buffer = model.buffers[std::size_t(view.buffer)].data;
    if (view.byteOffset > buffer.size() || view.byteLength > buffer.size() - view.byteOffset)
        throw_error(
            "{}: image buffer view {} reads past the end of its buffer (truncated file?)", path, view_index);
    base = buffer.data() + view.byteOffset;
    length = view.byteLength;
}

Image decode_base_colour(tinygltf::Image& gltf_image, int index, const std::string& path) {
    const bool external = !gltf_image.uri.empty() && gltf_image.uri.rfind("data:", 0) != 0;
    if (external) {
        const std::string file = (fs::path(path).parent_path() / gltf_image.uri).string();
        return read_image(file);
    }
    // Decoded by tdf's own PNG/JPEG reader (size limits checked before allocating), expanded
    // to RGBA as tinygltf's stb decoder did: grey -> (g, g, g), missing alpha -> 1.
    const std::string encoded(gltf_image.image.begin(), gltf_image.image.end());
    const Image decoded = decode_image(encoded, fmt::format("{}#image{}", path, index));
    const int c = decoded.channels();
    Image out(decoded.width(), decoded.height(), 4, 1.f);
    for (int y = 0; y < out.height(); ++y)
        for (int x = 0; x < out.width(); ++x) {
            for (int k = 0; k < 3; ++k) out.at(x, y, k) = decoded.at(x, y, c >= 3 ? k : 0);
            if (c == 2 || c == 4) out.at(x, y, 3) = decoded.at(x, y, c - 1);
        }
    return out;
}

struct Builder {
    TriangleMesh mesh;
    std::unordered_map<std::string, int> welded;  // position bits -> index
    bool any_uvs = false, any_colors = false;
    int base_colour_texture = -1;  // texture index
    std::vector<double> base_colour_factor;
    std::vector<Vec3f> colors;     // per position
    std::vector<std::uint8_t> has_color;

    int position_index(Vec3f p) {
        std::string key(reinterpret_cast<const char*>(&p), sizeof(p));
        auto [it, inserted] = welded.emplace(std::move(key), int(mesh.positions.size()));
        if (inserted) {
            mesh.positions.push_back(p);
            colors.push_back({1, 1, 1});
            has_color.push_back(0);
        }
        return it->second;
    }
};

// `group` says where the primitive came from; it is recorded as a FaceGroup when the primitive
// adds faces.
void add_primitive(Builder& b, const GltfReader& reader, const tinygltf::Model& model,
                   const tinygltf::Primitive& prim, const Mat4d& m, const std::string& path,
                   FaceGroup group) {
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) {
        log_warning("{}: skipping a primitive with mode {} (only triangles are read)", path, prim.mode);
        return;
    }
    const auto pos_it = prim.attributes.find("POSITION");
    if (pos_it == prim.attributes.end()) throw_error("{}: a primitive has no POSITION attribute", path);
    const std::vector<float> pos = reader.read_floats(pos_it->second, 3, "POSITION");
    const std::size_t n = pos.size() / 3;
    std::vector<float> uv, col;
    if (auto it = prim.attributes.find("TEXCOORD_0"); it != prim.attributes.end()) {
        uv = reader.read_floats(it->second, 2, "TEXCOORD_0");
        if (uv.size() / 2 != n) throw_error("{}: TEXCOORD_0 has {} elements, POSITION {}", path, uv.size() / 2, n);
    }
    if (auto it = prim.attributes.find("COLOR_0"); it != prim.attributes.end()) {
        col = reader.read_floats(it->second, 3, "COLOR_0");
        if (col.size() / 3 != n) throw_error("{}: COLOR_0 has {} elements, POSITION {}", path, col.size() / 3, n);
    }
    std::vector<int> index(n);
    for (std::size_t i = 0; i < n; ++i) {
        const float x = pos[3 * i], y = pos[3 * i + 1], z = pos[3 * i + 2];
        const Vec3f p{float(m[0] * x + m[4] * y + m[8] * z + m[12]), float(m[1] * x + m[5] * y + m[9] * z + m[13]),
                      float(m[2] * x + m[6] * y + m[10] * z + m[14])};
        index[i] = b.position_index(p);
        if (!col.empty() && !b.has_color[std::size_t(index[i])]) {
            b.colors[std::size_t(index[i])] = {col[3 * i], col[3 * i + 1], col[3 * i + 2]};
            b.has_color[std::size_t(index[i])] = 1;
        }
    }
    // One UV vertex per glTF vertex; glTF's v points down the image, tdf's up (OBJ convention).
    const int uv_base = int(b.mesh.uvs.size());
    for (std::size_t i = 0; i < n; ++i)
        b.mesh.uvs.push_back(uv.empty() ? Vec2f{0, 0} : Vec2f{uv[2 * i], 1.f - uv[2 * i + 1]});
    b.any_uvs |= !uv.empty();
    b.any_colors |= !col.empty();

    std::vector<std::uint32_t> corners;
    if (prim.indices >= 0) {
        corners = reader.read_indices(prim.indices);
    } else {
        corners.resize(n);
        for (std::size_t i = 0; i < n; ++i) corners[i] = std::uint32_t(i);
    }
    if (corners.size() % 3 != 0) throw_error("{}: a triangle primitive has {} indices, not a multiple of 3", path, corners.size());
    const bool mirrored = determinant3(m) < 0;  // keep counter-clockwise = front
    if (!corners.empty()) {
        if (prim.material >= 0 && std::size_t(prim.material) < model.materials.size()) {
            group.gltf_material = prim.material;
            group.material = model.materials[std::size_t(prim.material)].name;
        }
        group.world_from_node = m;
        b.mesh.face_groups.push_back(std::move(group));
    }
    for (std::size_t t = 0; t < corners.size(); t += 3) {
        std::uint32_t c[3] = {corners[t], corners[t + 1], corners[t + 2]};
        for (std::uint32_t k : c)
            if (k >= n) throw_error("{}: vertex index {} is out of range ({} vertices)", path, k, n);
        if (mirrored) std::swap(c[1], c[2]);
        b.mesh.triangles.push_back({index[c[0]], index[c[1]], index[c[2]]});
        b.mesh.face_group.push_back(int(b.mesh.face_groups.size()) - 1);
        b.mesh.uv_triangles.push_back({uv_base + int(c[0]), uv_base + int(c[1]), uv_base + int(c[2])});
    }
    if (prim.material >= 0 && std::size_t(prim.material) < model.materials.size()) {
        const auto& pbr = model.materials[std::size_t(prim.material)].pbrMetallicRoughness;
        if (pbr.baseColorTexture.index >= 0) {
            if (b.base_colour_texture >= 0 && b.base_colour_texture != pbr.baseColorTexture.index)
                log_warning("{}: several base colour textures; using the first", path);
            else if (b.base_colour_texture < 0) {
                b.base_colour_texture = pbr.baseColorTexture.index;
                b.base_colour_factor = pbr.baseColorFactor;
                if (pbr.baseColorTexture.texCoord != 0)
                    log_warning("{}: base colour texture uses TEXCOORD_{}; reading TEXCOORD_0", path,
                                pbr.baseColorTexture.texCoord);
            }
        }
    }
}

void visit(Builder& b, const GltfReader& reader, const tinygltf::Model& model, int node_index, const Mat4d& parent,
           const std::string& path, int depth) {
    if (node_index < 0 || std::size_t(node_index) >= model.nodes.size())
        throw_error("{}: node {} does not exist", path, node_index);
    if (depth > 64) throw_error("{}: the node hierarchy is deeper than 64 (a cycle?)", path);
    const tinygltf::Node& node = model.nodes[std::size_t(node_index)];
    const Mat4d m = multiply(parent, node_matrix(node));
    if (node.mesh >= 0) {
        if (std::size_t(node.mesh) >= model.meshes.size()) throw_error("{}: mesh {} does not exist", path, node.mesh);
        const tinygltf::Mesh& mesh = model.meshes[std::size_t(node.mesh)];
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            FaceGroup group;
            group.object = node.name;
            group.group = mesh.name;
            group.gltf_node = node_index;
            group.gltf_mesh = node.mesh;
            group.gltf_primitive = int(p);
            add_primitive(b, reader, model, mesh.primitives[p], m, path, std::move(group));
        }
    }
    for (int child : node.children) visit(b, reader, model, child, m, path, depth + 1);
}

}  // namespace

TriangleMesh load_gltf(const std::string& path, const MeshLoadOptions& options) {
    if (!fs::exists(path)) throw_error("cannot open '{}': no such file", path);
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&keep_encoded_image, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    const bool binary = lower_extension(path) == ".glb";
    const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                           : loader.LoadASCIIFromFile(&model, &err, &warn, path);
    if (!ok) {
        // tinygltf messages may span lines; keep the first.
        const std::string first = err.substr(0, err.find('\n'));
        throw_error("'{}': cannot read glTF: {}", path, first.empty() ? "unknown error" : first);
    }
    const GltfReader reader(model, path);
    Builder b;
    std::vector<int> roots;
    if (!model.scenes.empty()) {
        const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
        if (std::size_t(scene) >= model.scenes.size()) throw_error("{}: default scene {} does not exist", path, scene);
        roots = model.scenes[std::size_t(scene)].nodes;
    } else {
        for (std::size_t i = 0; i < model.nodes.size(); ++i) roots.push_back(int(i));
    }
    for (int root : roots) visit(b, reader, model, root, identity(), path, 0);
    if (b.mesh.triangles.empty()) throw_error("'{}': no triangles in the default scene", path);
    TriangleMesh& mesh = b.mesh;
    if (!b.any_uvs) {
        mesh.uvs.clear();
        mesh.uv_triangles.clear();
    }
    if (b.any_colors) mesh.colors = b.colors;
    if (options.load_textures && b.base_colour_texture >= 0) {
        if (std::size_t(b.base_colour_texture) >= model.textures.size())
            throw_error("{}: texture {} does not exist", path, b.base_colour_texture);
        const int source = model.textures[std::size_t(b.base_colour_texture)].source;
        if (source < 0 || std::size_t(source) >= model.images.size())
            throw_error("{}: texture {} has no valid image", path, b.base_colour_texture);
        tinygltf::Image& image = model.images[std::size_t(source)];
        if (image.bufferView >= 0) {
            const unsigned char* base = nullptr;
            std::size_t length = 0;
            embedded_image_bytes(model, image.bufferView, path, base, length);
            image.image.assign(base, base + length);
        }
        mesh.albedo = decode_base_colour(image, source, path);
        mesh.albedo_path = image.uri.empty() || image.uri.rfind("data:", 0) == 0
                               ? fmt::format("{}#image{}", path, source)
                               : (fs::path(path).parent_path() / image.uri).string();
        // baseColorFactor multiplies the texture (glTF 2.0 spec 3.9.2).
        if (b.base_colour_factor.size() == 4)
            for (int y = 0; y < mesh.albedo.height(); ++y)
                for (int x = 0; x < mesh.albedo.width(); ++x)
                    for (int c = 0; c < std::min(4, mesh.albedo.channels()); ++c)
                        mesh.albedo.at(x, y, c) *= float(b.base_colour_factor[std::size_t(c)]);
    }
    mesh.source_path = path;
    finish_loaded_mesh(mesh, path, options);
    return mesh;
}

}  // namespace tdf
