// Quality measures of a UV layout (AtlasReport) and their JSON / text forms.
#include <fmt/format.h>
#include <tdf/atlas/uv_atlas.h>
#include <tdf/atlas/uv_metrics.h>
#include <tdf/atlas/uv_raster.h>
#include <tdf/core/error.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numeric>

namespace tdf {

namespace {

int find_root(std::vector<int>& parent, int x) {
    while (parent[std::size_t(x)] != x)
        x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
    return x;
}

}  // namespace

std::size_t count_uv_overlaps(const TriangleMesh& mesh) {
    if (!mesh.has_uvs()) throw_error("{}: the mesh has no UVs", mesh.source_path);
    return count_overlapping_pairs(mesh.uvs, mesh.uv_triangles);
}

AtlasReport measure_atlas(const TriangleMesh& mesh, int size) {
    if (!mesh.has_uvs())
        throw_error("{}: cannot measure the UV layout of a mesh without UVs", mesh.source_path);
    AtlasReport r;
    r.size = size;
    r.faces = mesh.triangles.size();
    const double diagonal = std::max(double(length(compute_bounds(mesh).extent())), 1e-30);
    const double min_area = 1e-14 * diagonal * diagonal;

    // Charts = faces connected through shared UV vertices.
    std::vector<int> parent(mesh.uvs.size());
    std::iota(parent.begin(), parent.end(), 0);
    for (const Vec3i& t : mesh.uv_triangles) {
        parent[std::size_t(find_root(parent, t.y))] = find_root(parent, t.x);
        parent[std::size_t(find_root(parent, t.z))] = find_root(parent, t.x);
    }
    std::vector<double> chart_area(mesh.uvs.size(), 0.0);
    std::vector<std::uint8_t> used(mesh.uvs.size(), 0);

    double sum_stretch = 0, sum_area3 = 0, sum_area_uv = 0, max_stretch_squared = 0, angle_sum = 0;
    std::size_t measured = 0;
    std::vector<double> collapsed_areas;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Vec3i& t = mesh.triangles[f];
        const Vec3i& ti = mesh.uv_triangles[f];
        const std::array<Vec3f, 3> q = {mesh.positions[std::size_t(t.x)],
                                        mesh.positions[std::size_t(t.y)],
                                        mesh.positions[std::size_t(t.z)]};
        const std::array<Vec2f, 3> p = {
            mesh.uvs[std::size_t(ti.x)], mesh.uvs[std::size_t(ti.y)], mesh.uvs[std::size_t(ti.z)]};
        const double area3 = triangle_area(q[0], q[1], q[2]);
        const double area2 = signed_uv_area2(p[0], p[1], p[2]);
        const bool degenerate = !(area3 > min_area);
        r.degenerate_faces += degenerate;
        bool inside = std::isfinite(area2);
        for (const Vec2f uv : p)
            inside = inside && uv.x >= -1e-6f && uv.x <= 1 + 1e-6f && uv.y >= -1e-6f && uv.y <= 1 + 1e-6f;
        if (!inside) {
            ++r.unmapped_faces;
            continue;
        }
        const int root = find_root(parent, ti.x);
        chart_area[std::size_t(root)] += area2;
        used[std::size_t(root)] = 1;
        if (degenerate) continue;
        if (area2 == 0.0) {  // judged below, once the layout's texel density is known
            collapsed_areas.push_back(area3);
            continue;
        }
        r.flipped_triangles += area2 < 0;
        const double stretch = l2_stretch_squared(q, p);
        sum_stretch += stretch * area3;
        sum_area3 += area3;
        sum_area_uv += 0.5 * std::abs(area2);
        max_stretch_squared = std::max(max_stretch_squared, stretch);
        const AngleDistortion angles = angle_distortion(q, p);
        angle_sum += angles.sum;
        r.angle_distortion_max = std::max(r.angle_distortion_max, angles.max);
        ++measured;
    }
    for (std::size_t v = 0; v < mesh.uvs.size(); ++v)
        if (used[v] && find_root(parent, int(v)) == int(v)) {
            ++r.chart_count;
            r.mirrored_charts += chart_area[v] < 0;
        }
    // A face with area but none in UV is unmapped unless it is far below a texel at the
    // layout's density (a needle whose UVs rounded together): it still sits on its chart.
    const double texels_per_area =
        sum_area3 > 0 ? sum_area_uv / sum_area3 * double(size) * double(size) : 0.0;
    for (const double area3 : collapsed_areas) r.unmapped_faces += area3 * texels_per_area >= 1e-3;
    if (sum_area3 > 0) {
        // Normalize so that a uniformly scaled isometry measures exactly 1 (Sander et al. 2001).
        const double normalization = std::sqrt(sum_area_uv / sum_area3);
        r.stretch_mean = std::sqrt(sum_stretch / sum_area3) * normalization;
        r.stretch_max = std::sqrt(max_stretch_squared) * normalization;
    }
    if (measured > 0) r.angle_distortion_mean = angle_sum / double(3 * measured);
    r.overlaps = count_overlapping_pairs(mesh.uvs, mesh.uv_triangles);
    if (size > 0)
        r.utilisation = double(rasterize_uv(mesh, size).covered_count()) / (double(size) * double(size));
    return r;
}

std::string atlas_report_json(const AtlasReport& r) {
    const nlohmann::json j = {{"size", r.size},
                              {"faces", r.faces},
                              {"charts", r.chart_count},
                              {"utilisation", r.utilisation},
                              {"stretch_l2_mean", r.stretch_mean},
                              {"stretch_l2_max", r.stretch_max},
                              {"angle_distortion_mean_degrees", r.angle_distortion_mean},
                              {"angle_distortion_max_degrees", r.angle_distortion_max},
                              {"overlaps", r.overlaps},
                              {"mirrored_charts", r.mirrored_charts},
                              {"flipped_triangles", r.flipped_triangles},
                              {"unmapped_faces", r.unmapped_faces},
                              {"degenerate_faces", r.degenerate_faces},
                              {"reunwrapped", r.reunwrapped},
                              {"seconds", r.seconds}};
    return j.dump(2) + "\n";
}

std::string format_atlas_report(const AtlasReport& r) {
    return fmt::format(
        "atlas {}x{} ({}): {} faces, {} charts, utilisation {:.1f} %\n"
        "  L2 stretch mean {:.4f} max {:.3f}; angle distortion mean {:.2f} max {:.1f} degrees\n"
        "  overlaps {}, mirrored charts {}, flipped triangles {}, unmapped faces {} ({} zero-area faces)\n"
        "  time {:.2f} s\n",
        r.size,
        r.size,
        r.reunwrapped ? "new" : "kept",
        r.faces,
        r.chart_count,
        100.0 * r.utilisation,
        r.stretch_mean,
        r.stretch_max,
        r.angle_distortion_mean,
        r.angle_distortion_max,
        r.overlaps,
        r.mirrored_charts,
        r.flipped_triangles,
        r.unmapped_faces,
        r.degenerate_faces,
        r.seconds);
}

}  // namespace tdf
