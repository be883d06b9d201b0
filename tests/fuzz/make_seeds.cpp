// Writes the seed corpora of the fuzz harnesses: small valid files of every kind each reader
// accepts, and a few edge cases (empty, truncated, extreme headers). Run by scripts/fuzz.sh:
//   make_fuzz_seeds <folder>    -> <folder>/<target>/<name>
// The inputs use the harnesses' conventions (tests/fuzz/fuzz_targets.h: parts joined by
// kPartSeparator), so the same bytes replay through tdf_fuzz_regression_tests.
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_writer.h>
#include <tdf/scene/procedural_mesh.h>
#include <zlib.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "fuzz/fuzz_targets.h"

namespace fs = std::filesystem;
using namespace tdf;

namespace {

std::string g_root;
const std::string kSep = fuzz::kPartSeparator;

void seed(const std::string& target, const std::string& name, const std::string& bytes) {
    const fs::path folder = fs::path(g_root) / target;
    fs::create_directories(folder);
    std::ofstream out(folder / name, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

std::string scratch(const std::string& name) { return (fs::path(g_root) / ".scratch" / name).string(); }

template <typename T>
void put(std::string& s, T value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    s.append(bytes, sizeof(T));
}

Image gradient(int w, int h, int channels) {
    Image image(w, h, channels);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < channels; ++c) image.at(x, y, c) = float((x + 2 * y + 3 * c) % 7) / 6.f;
    return image;
}

void obj_seeds() {
    seed("obj",
         "triangle.obj",
         "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n");
    seed("obj",
         "quad_negative_colours.obj",
         "o quad\ng front\nv -1 -1 0 1 0 0\nv 1 -1 0 0 1 0\nv 1 1 0 0 0 1\nv -1 1 0 1 1 1\nusemtl red\nf -4 "
         "-3 -2 -1\n");
    seed("obj", "normals_only.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\ns off\nl 1 2\n");
    seed("obj",
         "with_mtl.obj",
         "mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n" +
             kSep + "newmtl m\nKd 1 1 1\nmap_Kd -s 1 1 1 missing.png\nnorm n.png\nmap_Bump -bm 1 n.png\n");
    seed("obj", "bad_index.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
    seed("obj", "zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    seed("obj", "huge_numbers.obj", "v 1e39 -1e39 nan\nv inf 0 0\nv 0 1 0\nf 1 2 3\nf 99999999999 1 2\n");
    seed("obj", "empty.obj", "");
    const std::string sphere = scratch("sphere.obj");
    write_obj(sphere, make_uv_sphere(1.f, 6, 4), ObjMaterial{"material", "albedo.png", "normal.png", "", 0, 0});
    seed("obj", "sphere.obj", read_text_file(sphere) + kSep + read_text_file(scratch("sphere.mtl")));
}

std::string base64(const std::string& bytes) {
    static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const unsigned v = (unsigned(std::uint8_t(bytes[i])) << 16) |
                           (unsigned(std::uint8_t(bytes[i + 1])) << 8) | unsigned(std::uint8_t(bytes[i + 2]));
        for (int k = 3; k >= 0; --k) out += table[(v >> (6 * k)) & 63];
    }
    if (i < bytes.size()) {
        unsigned v = unsigned(std::uint8_t(bytes[i])) << 16;
        if (i + 1 < bytes.size()) v |= unsigned(std::uint8_t(bytes[i + 1])) << 8;
        out += table[(v >> 18) & 63];
        out += table[(v >> 12) & 63];
        out += i + 1 < bytes.size() ? table[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

// A triangle: 3 float VEC3 positions, 3 float VEC2 UVs, 3 uint16 indices (+2 padding).
std::string triangle_buffer() {
    std::string b;
    const float p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const float uv[] = {0, 0, 1, 0, 0, 1};
    for (float v : p) put(b, v);
    for (float v : uv) put(b, v);
    for (std::uint16_t i : {0, 1, 2, 0}) put(b, i);
    return b;
}

std::string triangle_gltf(const std::string& uri, std::size_t length) {
    return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],)"
           R"("nodes":[{"mesh":0,"name":"n","translation":[0,0,1],"children":[]}],)"
           R"("meshes":[{"name":"m","primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"indices":2,"mode":4,"material":0}]}],)"
           R"("materials":[{"name":"mat","pbrMetallicRoughness":{"baseColorFactor":[1,1,1,1]}}],)"
           R"("accessors":[)"
           R"({"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)"
           R"({"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"},)"
           R"({"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}],)"
           R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":24},)"
           R"({"buffer":0,"byteOffset":60,"byteLength":6}],)"
           R"("buffers":[{"byteLength":)" +
           std::to_string(length) + R"(,"uri":")" + uri + R"("}]})";
}

void gltf_seeds() {
    const std::string buffer = triangle_buffer();
    seed("gltf",
         "triangle_data_uri.gltf",
         triangle_gltf("data:application/octet-stream;base64," + base64(buffer), buffer.size()));
    seed("gltf", "triangle_bin.gltf", triangle_gltf("in.bin", buffer.size()) + kSep + buffer);
    seed("gltf", "empty_object.gltf", R"({"asset":{"version":"2.0"}})");
    const std::string glb = scratch("sphere.glb");
    const Image albedo = gradient(4, 4, 3);
    write_glb(glb, make_uv_sphere(1.f, 5, 3), &albedo, &albedo);
    seed("gltf", "sphere.glb", read_text_file(glb));
}

void ply_seeds() {
    seed("ply",
         "ascii_colour_uv.ply",
         "ply\nformat ascii 1.0\ncomment c\nelement vertex 3\nproperty float x\nproperty float y\nproperty "
         "float z\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float s\nproperty float t\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0 255 0 0 0 0\n1 0 0 0 255 0 1 0\n0 1 0 0 0 255 0 1\n3 0 1 2\n");
    std::string binary =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float "
        "y\nproperty float z\n"
        "element face 1\nproperty list uchar uint vertex_indices\nend_header\n";
    const float p[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    for (float v : p) put(binary, v);
    put(binary, std::uint8_t(4));
    for (std::uint32_t i : {0u, 1u, 2u, 3u}) put(binary, i);
    seed("ply", "binary_quad.ply", binary);
    std::string big =
        "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty "
        "double z\n"
        "element face 1\nproperty list uchar short vertex_indices\nend_header\n";
    const double q[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    for (double v : q) {
        char bytes[8];
        std::memcpy(bytes, &v, 8);
        for (int k = 7; k >= 0; --k) big += bytes[k];
    }
    big += '\x03';
    for (int i : {0, 1, 2}) big += std::string{'\0', char(i)};
    seed("ply", "binary_big_endian.ply", big);
    seed("ply",
         "huge_count.ply",
         "ply\nformat binary_little_endian 1.0\nelement vertex 2147483647\nproperty float x\nproperty float "
         "y\n"
         "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
}

void image_seeds() {
    const std::string png8 = scratch("rgb8.png");
    write_png(png8, gradient(5, 3, 3), 8);
    seed("image", "rgb8.png", read_text_file(png8));
    const std::string png16 = scratch("gray16.png");
    write_png(png16, gradient(3, 4, 1), 16);
    seed("image", "gray16.png", read_text_file(png16));
    const std::string pngmeta = scratch("rgba_meta.png");
    write_png(pngmeta, gradient(2, 2, 4), ImageMetadata{{"tdf:mm_per_pixel", "0.05"}}, 8);
    seed("image", "rgba_meta.png", read_text_file(pngmeta));
    const std::string exr = scratch("layers.exr");
    write_exr(exr, {{"albedo", {"R", "G", "B"}, gradient(3, 2, 3)}, {"depth", {"Z"}, gradient(3, 2, 1)}});
    seed("image", "layers.exr", read_text_file(exr));
    const std::string half = scratch("half.exr");
    write_exr(half, gradient(4, 4, 2), ImageMetadata{{"tdf:mm_per_pixel", "0.1"}}, ExrPixelType::Half);
    seed("image", "half.exr", read_text_file(half));
    const std::string jpeg = scratch("rgb.jpg");
    write_jpeg(jpeg, gradient(9, 7, 3));
    seed("image", "rgb.jpg", read_text_file(jpeg));
    const std::string gray_jpeg = scratch("gray.jpg");
    write_jpeg(gray_jpeg, gradient(8, 8, 1));
    seed("image", "gray.jpg", read_text_file(gray_jpeg));
    seed("image", "truncated.png", read_text_file(png8).substr(0, 40));
}

std::string npy(const std::string& descr, const std::string& shape, const std::string& data,
                bool fortran = false, int major = 1) {
    std::string header = "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") +
                         ", 'shape': " + shape + ", }";
    const std::size_t prefix = major == 1 ? 10 : 12;
    while ((prefix + header.size() + 1) % 64 != 0) header += ' ';
    header += '\n';
    std::string out = "\x93NUMPY";
    out += char(major);
    out += '\0';
    if (major == 1)
        put(out, std::uint16_t(header.size()));
    else
        put(out, std::uint32_t(header.size()));
    return out + header + data;
}

// A zip archive of `members` (name, bytes), stored or deflated, with correct CRCs.
std::string zip(const std::vector<std::pair<std::string, std::string>>& members, bool compress) {
    std::string out, directory;
    for (const auto& [name, raw] : members) {
        std::string data = raw;
        if (compress) {
            z_stream s{};
            deflateInit2(&s, 9, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY);
            std::string buffer(deflateBound(&s, uLong(raw.size())), '\0');
            s.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(raw.data()));
            s.avail_in = uInt(raw.size());
            s.next_out = reinterpret_cast<Bytef*>(buffer.data());
            s.avail_out = uInt(buffer.size());
            deflate(&s, Z_FINISH);
            buffer.resize(s.total_out);
            deflateEnd(&s);
            data = buffer;
        }
        const std::uint32_t crc =
            std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(raw.data()), uInt(raw.size())));
        const std::uint32_t local = std::uint32_t(out.size());
        put(out, std::uint32_t(0x04034b50));
        put(out, std::uint16_t(20));
        put(out, std::uint16_t(0));
        put(out, std::uint16_t(compress ? 8 : 0));
        put(out, std::uint32_t(0));
        put(out, crc);
        put(out, std::uint32_t(data.size()));
        put(out, std::uint32_t(raw.size()));
        put(out, std::uint16_t(name.size()));
        put(out, std::uint16_t(0));
        out += name + data;
        put(directory, std::uint32_t(0x02014b50));
        put(directory, std::uint16_t(20));
        put(directory, std::uint16_t(20));
        put(directory, std::uint16_t(0));
        put(directory, std::uint16_t(compress ? 8 : 0));
        put(directory, std::uint32_t(0));
        put(directory, crc);
        put(directory, std::uint32_t(data.size()));
        put(directory, std::uint32_t(raw.size()));
        put(directory, std::uint16_t(name.size()));
        put(directory, std::uint16_t(0));
        put(directory, std::uint16_t(0));
        put(directory, std::uint16_t(0));
        put(directory, std::uint16_t(0));
        put(directory, std::uint32_t(0));
        put(directory, local);
        directory += name;
    }
    const std::uint32_t directory_at = std::uint32_t(out.size());
    out += directory;
    put(out, std::uint32_t(0x06054b50));
    put(out, std::uint16_t(0));
    put(out, std::uint16_t(0));
    put(out, std::uint16_t(members.size()));
    put(out, std::uint16_t(members.size()));
    put(out, std::uint32_t(directory.size()));
    put(out, directory_at);
    put(out, std::uint16_t(0));
    return out;
}

void npy_seeds() {
    std::string f8;
    for (double v : {0.0, 1.5, -2.0, 1e-3, 4.0, 5.0}) put(f8, v);
    const std::string a = npy("<f8", "(2, 3)", f8);
    seed("npy", "f8_2x3.npy", a);
    std::string f4;
    for (int i = 0; i < 12; ++i) put(f4, float(i) * 0.25f);
    seed("npy", "f4_fortran_2x3x2.npy", npy("<f4", "(2, 3, 2)", f4, true));
    seed(
        "npy", "i2_big_endian.npy", npy(">i2", "(2, 2)", std::string("\x00\x01\x00\x02\xff\xff\x80\x00", 8)));
    seed("npy", "u1_v2.npy", npy("|u1", "(3,)", "abc", false, 2));
    seed("npy", "f2_scalar.npy", npy("<f2", "()", std::string("\x00\x3c", 2)));
    seed("npy", "b1.npy", npy("|b1", "(2,)", std::string("\x00\x01", 2)));
    std::string huge;
    put(huge, 1e300);
    seed("npy", "f8_1e300.npy", npy("<f8", "(1,)", huge));
    seed("npy", "claims_large_shape.npy", npy("<f8", "(1099511627776, 2)", f8));
    const std::string b = npy("<f4", "(2, 3, 2)", f4);
    seed("npy", "stored.npz", zip({{"dm.npy", a}, {"gx.npy", b}}, false));
    seed("npy", "deflated.npz", zip({{"gx.npy", b}, {"gy.npy", b}}, true));
}

void tmd_seeds() {
    std::string tmd = "Binary TrueMap Data File v2.0\r\n";
    tmd += '\0';
    tmd += "comment";
    tmd += '\0';
    put(tmd, std::uint32_t(4));
    put(tmd, std::uint32_t(3));
    put(tmd, 0.4f);
    put(tmd, 0.3f);
    put(tmd, 0.f);
    put(tmd, 0.f);
    for (int i = 0; i < 12; ++i) put(tmd, float(i % 5) * 0.01f);
    seed("tmd", "4x3.tmd", tmd);
    seed("tmd", "truncated.tmd", tmd.substr(0, tmd.size() - 5));
}

void scene_seeds() {
    seed("scene", "minimal.json", R"({"mesh": "m.obj"})");
    seed(
        "scene",
        "full.json",
        R"({"mesh": "m.glb", "normalize": true, "normalize_bound": 0.8, "tangents": "reference",)"
        R"( "albedo": {"source": "constant", "color": [0.5, 0.2, 0.1]}, "tactile": {"images": ["t.png"]},)"
        R"( "label_map": "l.png", "image": {"width": 64, "height": 32}, "ssaa": 2, "shading": "training",)"
        R"( "background": 1, "passes": ["albedo", "mask"], "seed": 7,)"
        R"( "views": {"radius": 2.5, "fovy": 40, "target": [0, 0, 0], "orbit": [{"elevation": 10, "azimuth": 20}],)"
        R"( "turntable": {"count": 4, "elevation": 5}, "random": {"count": 2, "ssaa": true},)"
        R"( "patches": {"count": 1, "reference_flip": true}},)"
        R"( "light": {"mode": "magic3d", "ambient": 0.3, "position": [0, 1, 2]}, "optimize": {"iterations": 3}})");
    seed("scene",
         "overrides.json",
         R"({"mesh": "m.obj", "image": {"width": 16}})" + kSep +
             "image.height=8\nviews.orbit=[]\npasses=[\"albedo\"]\nseed=3\nmesh=other.obj\n");
    seed("scene",
         "parent.json",
         R"({"parent": "base.json", "ssaa": 1.5})" + kSep + "light.mode=point\n" + kSep +
             R"({"mesh": "m.ply", "views": {"turntable": {"count": 2}}})");
    seed("scene", "bad_values.json", R"({"mesh": "m.obj", "seed": 18446744073709551615, "ssaa": 1e999})");
    seed("scene", "duplicate_keys.json", R"({"mesh": "m.obj", "mesh": "n.obj"})");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: make_fuzz_seeds <folder>\n");
        return 2;
    }
    g_root = argv[1];
    try {
        fs::create_directories(fs::path(g_root) / ".scratch");
        obj_seeds();
        gltf_seeds();
        ply_seeds();
        image_seeds();
        npy_seeds();
        tmd_seeds();
        scene_seeds();
        fs::remove_all(fs::path(g_root) / ".scratch");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "make_fuzz_seeds: %s\n", e.what());
        return 1;
    }
    return 0;
}
