// Generates scenes/four_part_sphere, the shipped example with four parts of strongly different
// touched materials: a sphere cut into four latitude bands along wavy lines, each band its own
// OBJ material (the `mesh` parts source), colour and tactile map. The ground truth is also a
// face label file, so tests can pick any subset of bands (2, 3 or 4 parts) on the same mesh.
// Deterministic: `--check <folder>` (a ctest) regenerates the files and compares bytes.
//
//   tdf_make_four_part_scene <folder>            write the files below
//   tdf_make_four_part_scene --check <folder>    exit 1 if the folder's files differ
#include <tdf/atlas/gutter.h>
#include <tdf/atlas/uv_raster.h>
#include "generator_main.h"
#include "part_scene.h"
#include "tileable_normal_map.h"

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/rng.h>
#include <tdf/io/image_io.h>
#include <tdf/scene/procedural_mesh.h>

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <vector>

namespace {

using namespace tdf;

constexpr int kTextureSize = 256;
constexpr int kTactileSize = 128;
constexpr std::uint64_t kSeed = 20261203;
constexpr float kPi = 3.14159265f;
const char* const kNames[4] = {"ribs", "dimples", "weave", "grain"};
const char* const kFiles[] = {"sphere.obj",         "sphere.mtl",          "albedo.png",        "labels.txt",
                              "label_image.png",
                              "ribs_normal.png",    "dimples_normal.png",  "weave_normal.png",  "grain_normal.png"};
const Vec3f kColours[4] = {{0.25f, 0.50f, 0.22f}, {0.75f, 0.42f, 0.25f}, {0.30f, 0.35f, 0.70f}, {0.80f, 0.75f, 0.55f}};

// Ground truth: four latitude bands whose borders wave with different frequencies, so every
// border crosses chart rows at many angles.
std::vector<int> face_parts(const TriangleMesh& mesh) {
    std::vector<int> part(mesh.triangles.size());
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Vec3f c = tools::face_centroid(mesh, f);
        const float a = std::atan2(c.x, c.z);
        const float borders[3] = {0.40f + 0.12f * std::sin(3.f * a), 0.f + 0.15f * std::sin(2.f * a + 1.f),
                                  -0.40f + 0.12f * std::sin(4.f * a + 2.f)};
        int p = 0;
        while (p < 3 && c.y <= borders[p]) ++p;
        part[f] = p;
    }
    return part;
}

// Four tileable height fields (periods divide the map) of clearly different relief: strong
// vertical ribs, round dimples on a grid, a fine diagonal weave, and a weak random grain.
Image height_field(int material, Rng& rng) {
    Image h(kTactileSize, kTactileSize, 1, 0.f);
    for (int y = 0; y < kTactileSize; ++y)
        for (int x = 0; x < kTactileSize; ++x) {
            const float u = (float(x) + 0.5f) / kTactileSize, v = (float(y) + 0.5f) / kTactileSize;
            float value = 0;
            if (material == 0) value = std::sin(u * 2 * kPi * 8.f) * 3.0f;
            if (material == 1) value = -std::pow(std::max(0.f, std::cos(u * 2 * kPi * 6.f) * std::cos(v * 2 * kPi * 6.f)), 2.f) * 4.f;
            if (material == 2)
                value = (std::sin((u + v) * 2 * kPi * 16.f) + std::sin((u - v) * 2 * kPi * 16.f)) * 0.5f;
            if (material == 3) value = rng.uniform(-0.4f, 0.4f);
            h.at(x, y, 0) = value;
        }
    return h;
}

void write_all(const std::string& folder) {
    ensure_folder(folder);
    const TriangleMesh mesh = make_uv_sphere(0.8f, 48, 24);
    const std::vector<int> part = face_parts(mesh);
    write_text_atomically(folder + "/sphere.obj",
                          tools::part_obj_text(mesh, part, {kNames, kNames + 4},
                                               "four-part UV sphere, radius 0.8, 48 x 24 (tools/make_four_part_scene.cpp)",
                                               "four_part_sphere"));
    std::string mtl = "# four materials sharing one albedo texture\n";
    for (int k = 0; k < 4; ++k)
        mtl += fmt::format("newmtl {}\nKd {:.2f} {:.2f} {:.2f}\nmap_Kd albedo.png\n", kNames[k], kColours[k].x,
                           kColours[k].y, kColours[k].z);
    write_text_atomically(folder + "/sphere.mtl", mtl);
    std::string labels = "# ground truth: one label per triangle of sphere.obj, in file order\n";
    for (int p : part) labels += std::string(kNames[p]) + "\n";
    write_text_atomically(folder + "/labels.txt", labels);

    UvRaster raster = rasterize_uv(mesh, kTextureSize);
    add_partial_texels(mesh, raster);
    Rng rng(kSeed);
    Image albedo(kTextureSize, kTextureSize, 3, 0.f), label_image(kTextureSize, kTextureSize, 3, 0.f);
    const Vec3f label_colours[4] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}};  // part_colour's
    for (std::size_t i = 0; i < albedo.pixel_count(); ++i) {
        const int f = raster.triangle[i];
        if (f < 0) continue;
        const float grain = rng.uniform(-0.03f, 0.03f);
        for (int c = 0; c < 3; ++c) {
            albedo.data()[3 * i + std::size_t(c)] = kColours[part[std::size_t(f)]][c] + grain;
            label_image.data()[3 * i + std::size_t(c)] = label_colours[part[std::size_t(f)]][c];
        }
    }
    dilate_gutter(albedo, raster.triangle, 8);
    dilate_gutter(label_image, raster.triangle, 8);
    write_png(folder + "/albedo.png", albedo);
    write_png(folder + "/label_image.png", label_image);
    for (int k = 0; k < 4; ++k)
        write_png(folder + "/" + kNames[k] + "_normal.png", tools::tileable_normal_map(height_field(k, rng), 1.f));
}

}  // namespace

int main(int argc, char** argv) {
    return tdf::tools::generator_main(argc, argv, "make_four_part_scene",
                                      std::vector<std::string>(std::begin(kFiles), std::end(kFiles)), write_all);
}
