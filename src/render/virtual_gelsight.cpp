#include <tdf/render/virtual_gelsight.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/mesh/mesh_io.h>
#include <tdf/render/trace.h>
#include <tdf/scene/camera.h>
#include <tdf/tactile/normal_map.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace tdf {

namespace fs = std::filesystem;

namespace {

/// mm per mesh unit from the MTL's `disp -mm base gain file` line: gain mesh units span the
/// height map's range (max - min mm).
float mm_per_unit_from_mtl(const std::string& mtl_path, const HeightMap& height) {
    if (!fs::exists(mtl_path)) throw_error("{}: missing (the asset's material, with its disp line)", mtl_path);
    std::istringstream lines(read_text_file(mtl_path));
    std::string line;
    while (std::getline(lines, line)) {
        std::istringstream words(line);
        std::string key, option;
        double base = 0, gain = 0;
        if (!(words >> key) || key != "disp") continue;
        if (!(words >> option >> base >> gain) || option != "-mm" || !(gain > 0) || !std::isfinite(gain))
            throw_error("{}: the disp line '{}' is not 'disp -mm base gain file' with gain > 0", mtl_path, line);
        const auto [lo, hi] = std::minmax_element(height.height.values().begin(), height.height.values().end());
        if (!(*hi > *lo)) throw_error("{}: the height map is flat: no scale to read", height.source);
        return float(double(*hi - *lo) / gain);
    }
    throw_error("{}: no 'disp' line: the asset carries no height map scale (export it again with tdf optimize)",
                mtl_path);
}

Vec3f interpolate(const std::vector<Vec3f>& values, const Vec3i& corners, Vec3f b) {
    return values[std::size_t(corners[0])] * b.x + values[std::size_t(corners[1])] * b.y +
           values[std::size_t(corners[2])] * b.z;
}

TouchPoint touch_point(const TriangleMesh& mesh, int face, Vec3f b) {
    TouchPoint p;
    p.triangle = face;
    const auto& corners = mesh.triangles[std::size_t(face)];
    p.position = interpolate(mesh.positions, corners, b);
    p.normal = normalize_or_zero(interpolate(mesh.normals, corners, b));
    if (mesh.has_uvs()) {
        const auto& uvc = mesh.uv_triangles[std::size_t(face)];
        p.uv = mesh.uvs[std::size_t(uvc[0])] * b.x + mesh.uvs[std::size_t(uvc[1])] * b.y +
               mesh.uvs[std::size_t(uvc[2])] * b.z;
    }
    return p;
}

}  // namespace

std::unique_ptr<ReliefAsset> load_relief_asset(const std::string& folder) {
    if (!fs::is_directory(folder)) throw_error("{}: not a folder (give the output folder of tdf optimize)", folder);
    std::vector<std::string> stems;
    for (const auto& entry : fs::directory_iterator(folder)) {
        const fs::path p = entry.path();
        if (p.extension() == ".obj" && fs::exists(p.parent_path() / (p.stem().string() + "_height.exr")))
            stems.push_back(p.stem().string());
    }
    std::sort(stems.begin(), stems.end());
    // A run leaves <name> and <name>_initialized: the final asset is the one that is touched.
    if (stems.size() > 1)
        stems.erase(std::remove_if(stems.begin(), stems.end(),
                                   [&](const std::string& s) {
                                       const std::string tail = "_initialized";
                                       return s.size() > tail.size() &&
                                              s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
                                   }),
                    stems.end());
    if (stems.empty())
        throw_error("{}: no asset with a height map here (<name>.obj beside <name>_height.exr, as tdf optimize writes)",
                    folder);
    if (stems.size() > 1) throw_error("{}: {} assets with height maps ({}, {}, ...): give a folder with one", folder,
                                      stems.size(), stems[0], stems[1]);
    auto asset = std::make_unique<ReliefAsset>();
    const std::string base = (fs::path(folder) / stems[0]).string();
    asset->obj_path = base + ".obj";
    asset->height = read_height_map(base + "_height.exr");
    if (!(asset->height.mm_per_pixel > 0))
        throw_error("{}_height.exr: no tdf:mm_per_pixel: the texel size is unknown", base);
    asset->mm_per_unit = mm_per_unit_from_mtl(base + ".mtl", asset->height);
    asset->mesh = load_mesh(asset->obj_path);
    if (!asset->mesh.has_uvs()) throw_error("{}: the mesh has no UVs, so the height map cannot lie on it", asset->obj_path);
    asset->scene = std::make_unique<EmbreeScene>(asset->mesh);
    asset->height_texture = MipTexture(asset->height.height);
    return asset;
}

std::optional<TouchPoint> touch_point_at_uv(const TriangleMesh& mesh, Vec2f uv) {
    if (!mesh.has_uvs()) return std::nullopt;
    for (std::size_t f = 0; f < mesh.uv_triangles.size(); ++f) {
        const auto& c = mesh.uv_triangles[f];
        const Vec2f a = mesh.uvs[std::size_t(c[0])], b = mesh.uvs[std::size_t(c[1])], d = mesh.uvs[std::size_t(c[2])];
        const float det = (b.x - a.x) * (d.y - a.y) - (d.x - a.x) * (b.y - a.y);
        if (std::abs(det) < 1e-20f) continue;
        const float l1 = ((uv.x - a.x) * (d.y - a.y) - (d.x - a.x) * (uv.y - a.y)) / det;
        const float l2 = ((b.x - a.x) * (uv.y - a.y) - (uv.x - a.x) * (b.y - a.y)) / det;
        const float l0 = 1.0f - l1 - l2;
        const float eps = -1e-6f;
        if (l0 >= eps && l1 >= eps && l2 >= eps) {
            TouchPoint p = touch_point(mesh, int(f), {l0, l1, l2});
            p.uv = uv;
            return p;
        }
    }
    return std::nullopt;
}

std::vector<TouchPoint> random_touch_points(const TriangleMesh& mesh, int count, std::uint64_t seed) {
    std::vector<double> cumulative(mesh.triangles.size());
    double total = 0;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const auto& t = mesh.triangles[f];
        const Vec3f p0 = mesh.positions[std::size_t(t[0])];
        total += 0.5 * double(length(cross(mesh.positions[std::size_t(t[1])] - p0, mesh.positions[std::size_t(t[2])] - p0)));
        cumulative[f] = total;
    }
    TDF_CHECK(total > 0);
    Rng rng(seed);
    std::vector<TouchPoint> points;
    for (int k = 0; k < count; ++k) {
        const double pick = double(rng.uniform()) * total;
        const std::size_t f = std::size_t(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
        const float r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();  // uniform over the triangle
        points.push_back(touch_point(mesh, int(std::min(f, cumulative.size() - 1)),
                                     {1.0f - r1, r1 * (1.0f - r2), r1 * r2}));
    }
    return points;
}

SimulatedTouch simulate_touch(const ReliefAsset& asset, const TouchPoint& point, const GelSightPad& pad) {
    TDF_CHECK(pad.width >= 3 && pad.height >= 3 && pad.mm_per_pixel > 0 && asset.mm_per_unit > 0);
    const float units_per_mm = 1.0f / asset.mm_per_unit;
    const float half_height = 0.5f * float(pad.height) * pad.mm_per_pixel * units_per_mm;
    const float half_width = 0.5f * float(pad.width) * pad.mm_per_pixel * units_per_mm;
    // Above anything a convex or gently curved part raises under the pad.
    const float distance = 2.0f * std::max(half_width, half_height);
    Camera camera = Camera::tactile_patch(point.position, point.normal, pad.width, pad.height, distance, half_height);
    camera.near_plane = 0.0f;
    camera.far_plane = 4.0f * distance;
    const GBuffer g = trace_gbuffer(*asset.scene, asset.mesh, camera);
    std::size_t missed = 0;
    for (float m : g.mask) missed += m > 0 ? 0 : 1;
    if (missed > 0)
        throw_error("{}: a {:.3g} x {:.3g} mm pad at uv ({:.4g}, {:.4g}) is larger than the part it lands on ({} of {} "
                    "pixels miss the mesh; a smaller pad: --pad-pixels)",
                    asset.obj_path, float(pad.width) * pad.mm_per_pixel, float(pad.height) * pad.mm_per_pixel,
                    point.uv.x, point.uv.y, missed, g.pixel_count());
    SimulatedTouch touch;
    Image z(pad.width, pad.height, 1);
    parallel_for(g.pixel_count(), 1024, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            float relief = 0;
            asset.height_texture.sample_bilinear(g.uv[i], &relief);
            // Height along the pad's axis: the surface's own, plus the relief along its normal.
            z.data()[i] = (distance - g.depth[i]) * asset.mm_per_unit + relief * std::max(dot(g.normal[i], point.normal), 0.0f);
        }
    });
    const float lowest = *std::min_element(z.values().begin(), z.values().end());
    for (float& v : z.values()) v -= lowest;
    touch.height.height = std::move(z);
    touch.height.mm_per_pixel = pad.mm_per_pixel;
    touch.height.source = asset.obj_path;
    touch.normals = normals_from_height(touch.height.height, 1.0f / pad.mm_per_pixel);
    touch.preview = gelsight_preview(touch.normals);
    touch.triangles.assign(g.triangle.begin(), g.triangle.end());
    return touch;
}

Image gelsight_preview(const Image& normals) {
    TDF_CHECK(normals.channels() >= 3);
    Image out(normals.width(), normals.height(), 3);
    const float pi = 3.14159265358979f, up = std::sin(pi / 4), across = std::cos(pi / 4);
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        const float* n = normals.data() + p * std::size_t(normals.channels());
        for (int c = 0; c < 3; ++c) {
            const float a = 2.0f * pi * float(c) / 3.0f + pi / 2;
            const float lit = n[0] * across * std::cos(a) + n[1] * across * std::sin(a) + n[2] * up;
            // Flat gel is mid grey; a slope facing a light takes its colour.
            out.data()[3 * p + std::size_t(c)] = std::clamp(0.5f + (lit - up), 0.0f, 1.0f);
        }
    }
    return out;
}

}  // namespace tdf
