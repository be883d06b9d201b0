// Tangent handedness on a mirrored UV chart (tests/data/mirrored_chart): the relief a normal map
// draws must have the same sign in tdf's renderer, in a glTF viewer that uses the exported GLB's
// TANGENT (bitangent = cross(N, T) * w) and in one that computes MikkTSpace tangents itself (as
// viewers do when TANGENT is absent), on both sides of the mirror.
#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/mesh/mesh_writer.h>
#include <tdf/render/renderer.h>
#include <tdf/render/shading.h>
#include <tdf/render/trace.h>

#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>

#include "common/test_paths.h"

using namespace tdf;

namespace {

// The normal map: tilted toward +u and +v of the texture.
const Vec3f kTilt = normalize_or_zero({0.4f, 0.3f, 1.0f});

// What the tilt must give in world space: the plane faces +z, v runs along +y on both halves,
// u runs along +x on the right half and along -x on the mirrored left half.
Vec3f expected_normal(float x) { return normalize_or_zero({x > 0 ? kTilt.x : -kTilt.x, kTilt.y, kTilt.z}); }

TriangleMesh load_asset(TangentMode mode, const std::string& name = "mirrored_chart") {
    MeshLoadOptions options;
    options.load_textures = false;
    options.tangent_mode = mode;
    return load_mesh(test::source_dir() + "/tests/data/mirrored_chart/" + name + ".obj", options);
}

// tdf's renderer: the shading normal of every hit pixel, with the hit's world x.
std::vector<std::pair<float, Vec3f>> render_normals(const TriangleMesh& mesh) {
    const EmbreeScene scene(mesh);
    const Image tactile(4, 4, 3, 0.f);
    Image map = tactile;
    for (std::size_t p = 0; p < map.pixel_count(); ++p)
        for (int c = 0; c < 3; ++c) map.data()[3 * p + std::size_t(c)] = kTilt[c];
    const MipTexture texture(map);
    SurfaceMaterial material;
    material.tactile = &texture;
    RenderSettings settings;
    settings.shading = ShadingMode::Training;
    const Renderer renderer(mesh, scene, material, settings);
    const Camera camera = Camera::orbit(0, 0, 3, 60, 48, 48);
    const Frame frame = renderer.render(camera, Light{}, {Pass::ShadingNormal});
    const GBuffer g = trace_gbuffer(scene, mesh, camera);
    std::vector<std::pair<float, Vec3f>> out;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x) {
            const std::size_t i = g.index(x, y);
            if (!(g.mask[i] > 0.f) || std::fabs(g.position[i].x) < 0.05f) continue;
            const Image& n = frame.images[0];
            out.emplace_back(g.position[i].x, Vec3f{n.at(x, y, 0), n.at(x, y, 1), n.at(x, y, 2)});
        }
    return out;
}

// The corners of every triangle of a GLB, as a viewer reads them.
struct GltfCorner {
    Vec3f position, normal, tangent;
    float w = 0;
    Vec2f texcoord;
};
std::vector<std::array<GltfCorner, 3>> read_glb_triangles(const std::string& path) {
    const std::string bytes = read_text_file(path);
    std::uint32_t json_length = 0;
    std::memcpy(&json_length, bytes.data() + 12, 4);
    const auto json = nlohmann::json::parse(bytes.substr(20, json_length));
    const char* bin = bytes.data() + 20 + json_length + 8;
    const auto floats = [&](std::size_t accessor, std::size_t index, int components) {
        const auto& a = json["accessors"][accessor];
        const auto& view = json["bufferViews"][a["bufferView"].get<std::size_t>()];
        std::array<float, 4> v{};
        std::memcpy(v.data(),
                    bin + view["byteOffset"].get<std::size_t>() + index * 4 * std::size_t(components),
                    4 * std::size_t(components));
        return v;
    };
    std::vector<std::array<GltfCorner, 3>> triangles;
    for (const auto& mesh : json["meshes"])
        for (const auto& primitive : mesh["primitives"]) {
            const auto& attributes = primitive["attributes"];
            const auto& index_accessor = json["accessors"][primitive["indices"].get<std::size_t>()];
            const auto& index_view = json["bufferViews"][index_accessor["bufferView"].get<std::size_t>()];
            const std::size_t count = index_accessor["count"];
            for (std::size_t t = 0; t + 2 < count; t += 3) {
                std::array<GltfCorner, 3> corners;
                for (std::size_t k = 0; k < 3; ++k) {
                    std::uint32_t vertex = 0;
                    std::memcpy(&vertex, bin + index_view["byteOffset"].get<std::size_t>() + 4 * (t + k), 4);
                    const auto p = floats(attributes["POSITION"], vertex, 3);
                    const auto n = floats(attributes["NORMAL"], vertex, 3);
                    const auto tg = floats(attributes["TANGENT"], vertex, 4);
                    const auto uv = floats(attributes["TEXCOORD_0"], vertex, 2);
                    corners[k] = {
                        {p[0], p[1], p[2]}, {n[0], n[1], n[2]}, {tg[0], tg[1], tg[2]}, tg[3], {uv[0], uv[1]}};
                }
                triangles.push_back(corners);
            }
        }
    return triangles;
}

// MikkTSpace's per-face tangent and sign as a glTF viewer applies them without TANGENT: tangent
// along dP/ds, sign from dP/dt, with (s, t) = TEXCOORD_0, then the sign negated because glTF's t
// points down the image (three.js computeMikkTSpaceTangents(negateSign = true); Blender's
// importer flips t before MikkTSpace, which is the same). On a planar chart MikkTSpace's
// averaging over faces of equal sign leaves this per-face frame unchanged.
std::pair<Vec3f, float> mikktspace_face_tangent(const std::array<GltfCorner, 3>& c, Vec3f normal) {
    const Vec3f e1 = c[1].position - c[0].position, e2 = c[2].position - c[0].position;
    const Vec2f d1 = c[1].texcoord - c[0].texcoord, d2 = c[2].texcoord - c[0].texcoord;
    const float det = d1.x * d2.y - d2.x * d1.y;
    const Vec3f dp_ds = (e1 * d2.y - e2 * d1.y) / det;
    const Vec3f dp_dt = (e2 * d1.x - e1 * d2.x) / det;
    const Vec3f tangent = normalize_or_zero(dp_ds - normal * dot(normal, dp_ds));
    const float sign = dot(cross(normal, tangent), dp_dt) > 0 ? 1.f : -1.f;
    return {tangent, -sign};
}

Vec3f viewer_normal(Vec3f normal, Vec3f tangent, float w) {
    const Vec3f bitangent = cross(normal, tangent) * w;  // glTF 2.0, meshes: TANGENT
    return normalize_or_zero(tangent * kTilt.x + bitangent * kTilt.y + normal * kTilt.z);
}

}  // namespace

// mirrored_chart: the mirrored half has its own UV region and seam UVs. mirrored_shared_seam: both
// halves share one UV region and the seam's UVs (the usual symmetric layout).
class TangentHandedness : public ::testing::TestWithParam<const char*> {};

TEST_P(TangentHandedness, MirroredChartHasTheSameReliefInTdfGltfTangentsAndMikkTSpace) {
    const std::string name = GetParam();
    const TriangleMesh mesh = load_asset(TangentMode::Handed, name);
    ASSERT_TRUE(mesh.has_uvs());

    // 1. tdf's renderer, both sides of the mirror.
    int left = 0, right = 0;
    double tdf_error = 0;
    for (const auto& [x, n] : render_normals(mesh)) {
        (x < 0 ? left : right) += 1;
        tdf_error = std::max(tdf_error, double(length(n - expected_normal(x))));
    }
    ASSERT_GT(left, 100);
    ASSERT_GT(right, 100);
    EXPECT_LT(tdf_error, 1e-3) << "tdf's shading normal differs from the relief the map describes";

    // 2. The exported GLB, read as a viewer reads it. With the tilted map as normalTexture (and
    // an OBJ + MTL + PNG beside it), so the same files can be opened in other programs by hand.
    Image encoded(8, 8, 3);
    for (std::size_t p = 0; p < encoded.pixel_count(); ++p)
        for (int c = 0; c < 3; ++c) encoded.data()[3 * p + std::size_t(c)] = (kTilt[c] + 1.f) * 0.5f;
    const std::string folder = test::scratch_dir();
    write_png(folder + "/" + name + "_normal.png", encoded, 8, Quantize::Truncate);
    write_obj(folder + "/" + name + ".obj", mesh, ObjMaterial{"tilted", "", name + "_normal.png", "", 0, 0});
    GlbMaps maps;
    maps.normal_png = read_text_file(folder + "/" + name + "_normal.png");
    const std::string path = folder + "/" + name + ".glb";
    write_glb(path, mesh, maps);
    const auto triangles = read_glb_triangles(path);
    ASSERT_EQ(triangles.size(), mesh.triangles.size());
    int mirrored = 0;
    double tangent_error = 0, mikk_error = 0;
    for (const auto& c : triangles) {
        const Vec3f centre = (c[0].position + c[1].position + c[2].position) / 3.f;
        const Vec3f normal = normalize_or_zero(c[0].normal + c[1].normal + c[2].normal);
        const Vec3f tangent = normalize_or_zero(c[0].tangent + c[1].tangent + c[2].tangent);
        EXPECT_EQ(c[0].w, c[1].w);
        EXPECT_EQ(c[0].w, c[2].w);
        EXPECT_EQ(c[0].w, centre.x < 0 ? -1.f : 1.f)
            << "TANGENT w on the " << (centre.x < 0 ? "mirrored" : "plain") << " side";
        mirrored += c[0].w < 0;
        tangent_error =
            std::max(tangent_error,
                     double(length(viewer_normal(normal, tangent, c[0].w) - expected_normal(centre.x))));
        const auto [mikk_tangent, mikk_sign] = mikktspace_face_tangent(c, normal);
        EXPECT_EQ(mikk_sign, c[0].w) << "MikkTSpace's sign disagrees with the exported TANGENT w";
        mikk_error = std::max(
            mikk_error,
            double(length(viewer_normal(normal, mikk_tangent, mikk_sign) - expected_normal(centre.x))));
    }
    EXPECT_EQ(mirrored, int(triangles.size() / 2));
    EXPECT_LT(tangent_error, 1e-5) << "a glTF viewer using TANGENT draws different relief";
    EXPECT_LT(mikk_error, 1e-5) << "a glTF viewer computing MikkTSpace tangents draws different relief";
}

INSTANTIATE_TEST_SUITE_P(Assets, TangentHandedness, ::testing::Values("mirrored_chart", "mirrored_shared_seam"));

TEST(TangentHandednessReference, ReferenceTangentsGetTheMirroredSideWrong) {
    // The reference discards handedness (TangentMode::Reference): the plain half is right, the
    // mirrored half draws relief that is not the map's. This is what the handed default fixes.
    // (Its per-position averaging also cancels the tangents of the two charts along the seam,
    // so only faces away from x = 0 are compared.)
    const TriangleMesh mesh = load_asset(TangentMode::Reference);
    int plain = 0, mirrored = 0;
    for (const auto& [x, n] : render_normals(mesh)) {
        if (std::fabs(x) < 0.55f) continue;
        const float error = length(n - expected_normal(x));
        if (x > 0) {
            EXPECT_LT(error, 1e-3f);
            ++plain;
        } else {
            EXPECT_GT(error, 0.5f);
            ++mirrored;
        }
    }
    EXPECT_GT(plain, 50);
    EXPECT_GT(mirrored, 50);
}
