// Generates the assets of scenes/two_part_sphere, the shipped multi-part example: a sphere whose
// upper part ("cap", green with lighter spots) and lower part ("base", terracotta with darker
// bands) meet along a wavy line, with the ground truth in three forms (OBJ materials, a per-face
// label file, a label image) so every parts source can be checked against it. Deterministic:
// `--check <folder>` (a ctest) regenerates the files and compares bytes.
//
//   tdf_make_two_part_scene <folder>            write the files below
//   tdf_make_two_part_scene --check <folder>    exit 1 if the folder's files differ
#include <tdf/atlas/gutter.h>
#include <tdf/atlas/uv_raster.h>
#include "generator_main.h"
#include "part_scene.h"

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/rng.h>
#include <tdf/io/image_io.h>
#include <tdf/scene/procedural_mesh.h>

#include <fmt/format.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace {

using namespace tdf;

constexpr int kTextureSize = 256;
constexpr int kTactileSize = 128;
constexpr std::uint64_t kSeed = 20261201;
constexpr float kPi = 3.14159265f;
const char* const kFiles[] = {
    "sphere.obj", "sphere.mtl", "albedo.png", "labels.txt", "label_image.png", "ribs_normal.png"};

// Ground truth: face f is in the cap (0) when its centroid lies above a wavy line of latitude.
std::vector<int> face_parts(const TriangleMesh& mesh) {
    std::vector<int> part(mesh.triangles.size());
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Vec3f c = tools::face_centroid(mesh, f);
        part[f] = c.y > 0.12f + 0.18f * std::sin(3.f * std::atan2(c.x, c.z)) ? 0 : 1;
    }
    return part;
}

// Smooth tileable value noise in [0, 1] (a few octaves of random lattice values).
float value_noise(const std::vector<float>& lattice, int n, float x, float y) {
    const float fx = std::floor(x), fy = std::floor(y);
    const float ax = x - fx, ay = y - fy;
    const auto at = [&](int i, int j) {
        return lattice[std::size_t(((j % n) + n) % n * n + ((i % n) + n) % n)];
    };
    const int i = int(fx), j = int(fy);
    const float sx = ax * ax * (3 - 2 * ax), sy = ay * ay * (3 - 2 * ay);
    return (at(i, j) * (1 - sx) + at(i + 1, j) * sx) * (1 - sy) +
           (at(i, j + 1) * (1 - sx) + at(i + 1, j + 1) * sx) * sy;
}

void write_all(const std::string& folder) {
    ensure_folder(folder);
    const TriangleMesh mesh = make_uv_sphere(0.8f, 48, 24);
    const std::vector<int> part = face_parts(mesh);
    write_text_atomically(folder + "/sphere.obj",
                          tools::part_obj_text(mesh, part, {"cap", "base"},
                                               "two-part UV sphere, radius 0.8, 48 x 24 (tools/make_two_part_scene.cpp)",
                                               "two_part_sphere"));
    write_text_atomically(
        folder + "/sphere.mtl",
        "# two materials sharing one albedo texture\nnewmtl cap\nKd 0.3 0.55 0.25\nmap_Kd albedo.png\n"
        "newmtl base\nKd 0.7 0.38 0.25\nmap_Kd albedo.png\n");
    std::string labels = "# ground truth: one label per triangle of sphere.obj, in file order\n";
    for (int p : part) labels += p == 0 ? "cap\n" : "base\n";
    write_text_atomically(folder + "/labels.txt", labels);

    UvRaster raster = rasterize_uv(mesh, kTextureSize);
    add_partial_texels(mesh, raster);
    Rng rng(kSeed);
    constexpr int kLattice = 16;
    std::vector<float> lattice(kLattice * kLattice);
    for (float& v : lattice) v = rng.uniform();
    Image albedo(kTextureSize, kTextureSize, 3, 0.f), label_image(kTextureSize, kTextureSize, 3, 0.f);
    for (int y = 0; y < kTextureSize; ++y)
        for (int x = 0; x < kTextureSize; ++x) {
            const std::size_t i = std::size_t(y) * kTextureSize + std::size_t(x);
            const int f = raster.triangle[i];
            if (f < 0) continue;
            const float u = (float(x) + 0.5f) / kTextureSize, v = 1.f - (float(y) + 0.5f) / kTextureSize;
            const float noise = value_noise(lattice, kLattice, u * 16.f, v * 16.f) * 0.6f +
                                value_noise(lattice, kLattice, u * 48.f + 3.f, v * 48.f + 7.f) * 0.4f;
            const float grain = rng.uniform(-0.03f, 0.03f);
            Vec3f c;
            if (part[std::size_t(f)] == 0) {
                // Green cap with lighter spots (areoles).
                const float spot =
                    std::pow(std::max(0.f, std::sin(u * 2 * kPi * 24.f) * std::sin(v * 2 * kPi * 12.f)), 8.f);
                c = Vec3f{0.24f, 0.50f, 0.22f} * (0.8f + 0.4f * noise) + Vec3f{0.35f, 0.3f, 0.2f} * spot;
            } else {
                // Terracotta base with darker horizontal bands.
                const float band = 0.5f + 0.5f * std::sin(v * 2 * kPi * 10.f);
                c = Vec3f{0.72f, 0.40f, 0.26f} * (0.8f + 0.25f * noise - 0.15f * band);
            }
            for (int k = 0; k < 3; ++k) albedo.at(x, y, k) = std::clamp(c[k] + grain, 0.f, 1.f);
            label_image.at(x, y, part[std::size_t(f)] == 0 ? 0 : 1) = 1.f;
        }
    dilate_gutter(albedo, raster.triangle, 8);
    dilate_gutter(label_image, raster.triangle, 8);
    write_png(folder + "/albedo.png", albedo);
    write_png(folder + "/label_image.png", label_image);

    // Vertical ribs for the cap: height = |sin| ridges along u, tileable; OpenGL convention.
    Image ribs(kTactileSize, kTactileSize, 3);
    for (int y = 0; y < kTactileSize; ++y)
        for (int x = 0; x < kTactileSize; ++x) {
            const float u = (float(x) + 0.5f) / kTactileSize;
            const float slope = 1.2f * std::cos(u * 2 * kPi * 8.f);
            const Vec3f n = safe_normalize({-slope, 0.f, 1.f});
            for (int c = 0; c < 3; ++c) ribs.at(x, y, c) = n[c] * 0.5f + 0.5f;
        }
    write_png(folder + "/ribs_normal.png", ribs);
}

}  // namespace

int main(int argc, char** argv) {
    return tdf::tools::generator_main(argc, argv, "make_two_part_scene", std::vector<std::string>(std::begin(kFiles), std::end(kFiles)), write_all);
}
