// Generates the assets of scenes/pebble_sphere (mesh, albedo, tactile normal map) so the
// shipped example needs nothing outside the repository. Deterministic: the files it writes are
// committed, and `make_pebble_sphere --check <folder>` (a ctest) regenerates them and compares
// bytes, so the committed files provably come from this code.
//
//   tdf_make_pebble_sphere <folder>            write sphere.obj, albedo.png, tactile_normal.png
//   tdf_make_pebble_sphere --check <folder>    exit 1 if the folder's files differ
#include "generator_main.h"
#include "tileable_normal_map.h"

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/rng.h>
#include <tdf/io/image_io.h>
#include <tdf/scene/procedural_mesh.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

using namespace tdf;

constexpr int kTextureSize = 256;
constexpr int kPebbles = 90;
constexpr std::uint64_t kSeed = 20240611;

struct Pebble {
    float x, y;       // centre in texels (tileable)
    Vec3f colour;
};

std::vector<Pebble> make_pebbles() {
    Rng rng(kSeed);
    std::vector<Pebble> pebbles;
    for (int k = 0; k < kPebbles; ++k) {
        Pebble p;
        p.x = rng.uniform(0.f, float(kTextureSize));
        p.y = rng.uniform(0.f, float(kTextureSize));
        // Earthy greys and browns.
        const float base = rng.uniform(0.35f, 0.75f);
        p.colour = {base * rng.uniform(0.9f, 1.1f), base * rng.uniform(0.8f, 0.95f), base * rng.uniform(0.6f, 0.85f)};
        pebbles.push_back(p);
    }
    return pebbles;
}

// Distances to the nearest and second-nearest pebble centre with wrap-around (tileable).
void nearest_two(const std::vector<Pebble>& pebbles, float x, float y, int& nearest, float& d1, float& d2) {
    d1 = d2 = 1e30f;
    nearest = 0;
    for (int k = 0; k < int(pebbles.size()); ++k) {
        float dx = std::fabs(x - pebbles[std::size_t(k)].x), dy = std::fabs(y - pebbles[std::size_t(k)].y);
        dx = std::min(dx, float(kTextureSize) - dx);
        dy = std::min(dy, float(kTextureSize) - dy);
        const float d = std::sqrt(dx * dx + dy * dy);
        if (d < d1) {
            d2 = d1;
            d1 = d;
            nearest = k;
        } else if (d < d2) {
            d2 = d;
        }
    }
}

// Height in [0, 1]: rounded pebbles separated by grooves (distance to the Voronoi edge).
void pebble_fields(Image& height, Image& albedo) {
    const std::vector<Pebble> pebbles = make_pebbles();
    height = Image(kTextureSize, kTextureSize, 1);
    albedo = Image(kTextureSize, kTextureSize, 3);
    for (int y = 0; y < kTextureSize; ++y)
        for (int x = 0; x < kTextureSize; ++x) {
            int k;
            float d1, d2;
            nearest_two(pebbles, float(x) + 0.5f, float(y) + 0.5f, k, d1, d2);
            const float edge = std::min(1.f, 0.5f * (d2 - d1) / 12.f);  // 0 on the groove
            const float h = std::sqrt(edge * (2.f - edge));             // rounded profile
            height.at(x, y, 0) = h;
            const Vec3f c = pebbles[std::size_t(k)].colour * (0.55f + 0.45f * h);
            for (int ch = 0; ch < 3; ++ch) albedo.at(x, y, ch) = c[ch];
        }
}

std::string sphere_obj() {
    const TriangleMesh sphere = make_uv_sphere(0.8f, 48, 24);
    std::string text = "# UV sphere, radius 0.8, 48 segments x 24 rings (tools/make_pebble_sphere.cpp)\n";
    for (const Vec3f& p : sphere.positions) text += fmt::format("v {:.6f} {:.6f} {:.6f}\n", p.x, p.y, p.z);
    for (const Vec2f& t : sphere.uvs) text += fmt::format("vt {:.6f} {:.6f}\n", t.x, t.y);
    for (std::size_t f = 0; f < sphere.triangles.size(); ++f) {
        const Vec3i& p = sphere.triangles[f];
        const Vec3i& t = sphere.uv_triangles[f];
        text += fmt::format("f {}/{} {}/{} {}/{}\n", p.x + 1, t.x + 1, p.y + 1, t.y + 1, p.z + 1, t.z + 1);
    }
    return text;
}

void write_all(const std::string& folder) {
    ensure_folder(folder);
    Image height, albedo;
    pebble_fields(height, albedo);
    write_text_atomically(folder + "/sphere.obj", sphere_obj());
    write_png(folder + "/albedo.png", albedo);
    write_png(folder + "/tactile_normal.png", tools::tileable_normal_map(height, 10.f));
}

}  // namespace

int main(int argc, char** argv) {
    return tdf::tools::generator_main(argc, argv, "make_pebble_sphere", {"sphere.obj", "albedo.png", "tactile_normal.png"}, write_all);
}
