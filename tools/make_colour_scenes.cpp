// Generates two scenes whose base colour has what the pebble sphere lacks: near-black regions,
// saturated colours and a printed logo beside them (issue 29: refinement must not paint light
// into the albedo on meshes it has not seen). Deterministic: the files it writes are committed,
// and `--check` (a ctest) regenerates them and compares bytes.
//
//   scenes/dark_bottle:   a lathe-turned bottle (one chart, one seam): dark green glass, a
//                         black cap, a saturated red label with a white blocky logo and yellow
//                         rules; tactile map: a tileable field of round dimples and bumps.
//   scenes/painted_torus: a torus (genus 1, seams in both directions): a black and white checker
//                         band, saturated red / blue stripes, a yellow band with black dots;
//                         tactile map: tileable knurling (two crossed families of ridges).
//
//   tdf_make_colour_scenes <scenes folder>            write both scene folders
//   tdf_make_colour_scenes --check <scenes folder>    exit 1 if a committed file differs
#include "generator_main.h"
#include "tileable_normal_map.h"

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/rng.h>
#include <tdf/core/vec.h>
#include <tdf/io/image_io.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

using namespace tdf;

constexpr float kTwoPi = 6.28318530718f;
constexpr int kAlbedoSize = 512;
constexpr int kTactileSize = 256;

/// An OBJ of a surface given as position(u, v) on a (segments x rings) grid of the unit square,
/// positions shared across the u = 0/1 seam (and the v = 0/1 seam when `closed_v`), separate UV
/// vertices there. When `poles`, the first and last rows collapse to one position each (a lathe
/// profile that starts and ends on the axis) and the rows next to them are triangle fans.
std::string grid_obj(const std::string& comment, int segments, int rings, bool closed_v, bool poles,
                     const std::function<Vec3f(float, float)>& position) {
    std::string text = "# " + comment + " (tools/make_colour_scenes.cpp)\n";
    const int rows = closed_v ? rings : rings + 1;  // distinct position rows
    std::vector<std::vector<int>> index(std::size_t(rings + 1), std::vector<int>(std::size_t(segments)));
    int next = 1;
    for (int r = 0; r <= rings; ++r) {
        if (closed_v && r == rings) {
            index[std::size_t(r)] = index[0];
            continue;
        }
        const bool pole = poles && (r == 0 || r == rows - 1);
        for (int s = 0; s < segments; ++s) {
            if (pole && s > 0) {
                index[std::size_t(r)][std::size_t(s)] = index[std::size_t(r)][0];
                continue;
            }
            const Vec3f p = position(float(s) / float(segments), float(r) / float(rings));
            text += fmt::format("v {:.6f} {:.6f} {:.6f}\n", p.x, p.y, p.z);
            index[std::size_t(r)][std::size_t(s)] = next++;
        }
    }
    for (int r = 0; r <= rings; ++r)
        for (int s = 0; s <= segments; ++s)
            text += fmt::format("vt {:.6f} {:.6f}\n", float(s) / float(segments), float(r) / float(rings));
    const auto vt = [&](int r, int s) { return r * (segments + 1) + s + 1; };
    const auto v = [&](int r, int s) { return index[std::size_t(r)][std::size_t(s % segments)]; };
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            // Counter-clockwise seen from outside: u around, v up.
            const int a = v(r, s), b = v(r, s + 1), c = v(r + 1, s + 1), d = v(r + 1, s);
            if (!(poles && r == 0))
                text += fmt::format("f {}/{} {}/{} {}/{}\n", a, vt(r, s), b, vt(r, s + 1), c, vt(r + 1, s + 1));
            if (!(poles && r == rings - 1))
                text += fmt::format("f {}/{} {}/{} {}/{}\n", a, vt(r, s), c, vt(r + 1, s + 1), d, vt(r + 1, s));
        }
    return text;
}

/// Bottle profile: radius and height at t in [0, 1] from the bottom centre to the cap's centre.
Vec3f bottle_point(float u, float t) {
    // Piecewise profile (r, y), smooth enough at 64 rings: bottom disc, body, shoulder, neck, cap.
    struct Knot { float t, r, y; };
    static const Knot knots[] = {{0.00f, 0.00f, -0.80f}, {0.06f, 0.30f, -0.80f}, {0.10f, 0.34f, -0.76f},
                                 {0.55f, 0.34f, 0.20f},  {0.68f, 0.20f, 0.42f},  {0.76f, 0.12f, 0.52f},
                                 {0.86f, 0.12f, 0.70f},  {0.88f, 0.14f, 0.71f},  {0.96f, 0.14f, 0.82f},
                                 {1.00f, 0.00f, 0.82f}};
    std::size_t k = 1;
    while (k + 1 < std::size(knots) && knots[k].t < t) ++k;
    const Knot& a = knots[k - 1];
    const Knot& b = knots[k];
    const float w = std::clamp((t - a.t) / (b.t - a.t), 0.0f, 1.0f);
    const float s = w * w * (3.0f - 2.0f * w);  // smoothstep between knots
    const float r = a.r + (b.r - a.r) * s, y = a.y + (b.y - a.y) * s;
    const float angle = kTwoPi * u;
    return {r * std::sin(angle), y, r * std::cos(angle)};
}

Vec3f torus_point(float u, float v) {
    const float major = 0.6f, minor = 0.25f;
    const float a = kTwoPi * u, b = kTwoPi * v;
    const float ring = major + minor * std::cos(b);
    return {ring * std::sin(a), minor * std::sin(b), ring * std::cos(a)};
}

void set_rgb(Image& image, int x, int y, Vec3f c) {
    for (int ch = 0; ch < 3; ++ch) image.at(x, y, ch) = c[ch];
}

/// A 5x7 blocky glyph for the bottle's logo, row 0 on top.
bool glyph_pixel(char letter, int col, int row) {
    static const char* const kT[] = {"#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."};
    static const char* const kD[] = {"####.", "#...#", "#...#", "#...#", "#...#", "#...#", "####."};
    static const char* const kF[] = {"#####", "#....", "#....", "####.", "#....", "#....", "#...."};
    const char* const* g = letter == 'T' ? kT : letter == 'D' ? kD : kF;
    return g[row][col] == '#';
}

Image bottle_albedo() {
    Image albedo(kAlbedoSize, kAlbedoSize, 3);
    Rng rng(29001);
    std::vector<float> streak(static_cast<std::size_t>(kAlbedoSize));
    for (float& s : streak) s = rng.uniform(-0.012f, 0.012f);
    for (int y = 0; y < kAlbedoSize; ++y)
        for (int x = 0; x < kAlbedoSize; ++x) {
            const float t = 1.0f - (float(y) + 0.5f) / float(kAlbedoSize);  // v: bottom 0, top 1
            const float u = (float(x) + 0.5f) / float(kAlbedoSize);
            Vec3f c{0.05f, 0.10f, 0.06f};  // dark green glass, faint vertical streaks
            c = c + Vec3f{streak[std::size_t(x)], streak[std::size_t(x)], streak[std::size_t(x)]} * 0.5f;
            if (t > 0.86f) c = {0.025f, 0.025f, 0.03f};  // black cap
            if (t > 0.22f && t < 0.50f) {
                c = {0.74f, 0.03f, 0.05f};  // saturated red label
                if (std::fabs(t - 0.235f) < 0.006f || std::fabs(t - 0.485f) < 0.006f) c = {0.93f, 0.74f, 0.05f};
                // "TDF" twice around the bottle, letters 5x7 cells of 8 texels.
                const float cell = 8.0f / float(kAlbedoSize);
                for (float start : {0.15f, 0.65f}) {
                    const int row = int(std::floor((0.395f - t) / cell));
                    for (int letter = 0; letter < 3; ++letter) {
                        const float left = start + float(letter) * 6.0f * cell;
                        const int col = int(std::floor((u - left) / cell));
                        if (row >= 0 && row < 7 && col >= 0 && col < 5 && glyph_pixel("TDF"[letter], col, row))
                            c = {0.95f, 0.94f, 0.90f};
                    }
                }
            }
            set_rgb(albedo, x, y, c);
        }
    return albedo;
}

Image torus_albedo() {
    Image albedo(kAlbedoSize, kAlbedoSize, 3);
    for (int y = 0; y < kAlbedoSize; ++y)
        for (int x = 0; x < kAlbedoSize; ++x) {
            const float u = (float(x) + 0.5f) / float(kAlbedoSize), v = 1.0f - (float(y) + 0.5f) / float(kAlbedoSize);
            Vec3f c;
            if (u < 1.0f / 3.0f) {  // black and white checker, 8 x 8 squares
                const bool white = (int(u * 24.0f) + int(v * 8.0f)) % 2 == 0;
                c = white ? Vec3f{0.92f, 0.92f, 0.90f} : Vec3f{0.03f, 0.03f, 0.035f};
            } else if (u < 2.0f / 3.0f) {  // saturated red and blue stripes along the tube
                c = int(v * 12.0f) % 2 == 0 ? Vec3f{0.80f, 0.04f, 0.04f} : Vec3f{0.04f, 0.10f, 0.78f};
            } else {  // saturated yellow with black dots
                const float du = std::fmod(u * 24.0f, 1.0f) - 0.5f, dv = std::fmod(v * 8.0f, 1.0f) - 0.5f;
                c = du * du + dv * dv < 0.09f ? Vec3f{0.03f, 0.03f, 0.03f} : Vec3f{0.95f, 0.78f, 0.04f};
            }
            set_rgb(albedo, x, y, c);
        }
    return albedo;
}

Image dimples_height() {
    const int n = kTactileSize;
    Image h(n, n, 1, 0.0f);
    Rng rng(29002);
    for (int k = 0; k < 140; ++k) {
        const float cx = rng.uniform(0.f, float(n)), cy = rng.uniform(0.f, float(n));
        const float radius = rng.uniform(4.f, 9.f), depth = rng.uniform() < 0.7f ? -1.0f : 0.7f;
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                float dx = std::fabs(float(x) + 0.5f - cx), dy = std::fabs(float(y) + 0.5f - cy);
                dx = std::min(dx, float(n) - dx), dy = std::min(dy, float(n) - dy);
                const float r2 = (dx * dx + dy * dy) / (radius * radius);
                if (r2 < 1.0f) h.at(x, y, 0) += depth * radius * (1.0f - r2) * (1.0f - r2);
            }
    }
    return h;
}

Image knurl_height() {
    const int n = kTactileSize;
    Image h(n, n, 1);
    const float period = float(n) / 16.0f;  // tileable: 16 ridges per family across the map
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const float a = (float(x) + float(y)) / period, b = (float(x) - float(y)) / period;
            const auto ridge = [](float s) { return 1.0f - std::fabs(2.0f * (s - std::floor(s)) - 1.0f); };
            h.at(x, y, 0) = 3.0f * std::min(ridge(a), ridge(b));
        }
    return h;
}

std::string scene_json(const std::string& mesh, const std::string& object_name) {
    return fmt::format(R"({{
  "mesh": "{}",
  "albedo": {{ "source": "image", "image": "albedo.png" }},
  "tactile": {{ "images": ["tactile_normal.png"] }},
  "object_name": "{}",
  "image": {{ "width": 512, "height": 512 }},
  "shading": "visualizer",
  "passes": ["lambertian", "albedo", "mask", "tactile_normal"],
  "views": {{ "radius": 3, "fovy": 50, "orbit": [ {{ "elevation": -15, "azimuth": 0 }}, {{ "elevation": 30, "azimuth": 140 }} ] }},
  "light": {{ "mode": "camera", "relative_elevation": -20, "relative_azimuth": 30 }},
  "seed": 0
}}
)",
                       mesh, object_name);
}

const char* const kFiles[] = {"mesh.obj", "albedo.png", "tactile_normal.png", "scene.json"};

void write_scene(const std::string& folder, const std::string& obj, const Image& albedo, const Image& tactile,
                 const std::string& object_name) {
    ensure_folder(folder);
    write_text_atomically(folder + "/mesh.obj", obj);
    write_png(folder + "/albedo.png", albedo);
    write_png(folder + "/tactile_normal.png", tactile);
    write_text_atomically(folder + "/scene.json", scene_json("mesh.obj", object_name));
}

void write_all(const std::string& scenes) {
    write_scene(scenes + "/dark_bottle",
                grid_obj("lathe bottle, 64 segments x 64 rings, closed at both ends", 64, 64, false, true, bottle_point),
                bottle_albedo(), tools::tileable_normal_map(dimples_height(), 1.2f),
                "dark green glass bottle with a red label");
    write_scene(scenes + "/painted_torus",
                grid_obj("torus, major radius 0.6, minor 0.25, 96 x 32", 96, 32, true, false, torus_point),
                torus_albedo(), tools::tileable_normal_map(knurl_height(), 1.0f), "painted knurled ring");
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> files;
    for (const char* scene : {"dark_bottle", "painted_torus"})
        for (const char* name : kFiles) files.push_back(fmt::format("{}/{}", scene, name));
    return tdf::tools::generator_main(argc, argv, "make_colour_scenes", files, write_all);
}
