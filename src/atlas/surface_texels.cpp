#include <tdf/atlas/surface_texels.h>

#include <tdf/atlas/uv_metrics.h>
#include <tdf/core/error.h>
#include <tdf/mesh/uv_seams.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

/// The face's texel steps from its UV Jacobian: dP/du and dP/dv solved from two edges, T the
/// tangent-plane part of dP/du, B perpendicular to it on dP/dv's side.
bool face_step(const TriangleMesh& mesh, int face, int size, TexelStep& step) {
    const Vec3i& p = mesh.triangles[std::size_t(face)];
    const Vec3f q0 = mesh.positions[std::size_t(p[0])];
    const Vec3f e1 = mesh.positions[std::size_t(p[1])] - q0, e2 = mesh.positions[std::size_t(p[2])] - q0;
    const Vec2f t0 = corner_uv(mesh, face, 0), d1 = corner_uv(mesh, face, 1) - t0, d2 = corner_uv(mesh, face, 2) - t0;
    const float det = d1.x * d2.y - d2.x * d1.y;
    const Vec3f n = normalize_or_zero(cross(e1, e2));
    if (!(std::abs(det) > 1e-20f) || length_squared(n) == 0.0f) return false;
    const Vec3f dp_du = (e1 * d2.y - e2 * d1.y) / det, dp_dv = (e2 * d1.x - e1 * d2.x) / det;
    const Vec3f t = normalize_or_zero(dp_du - n * dot(n, dp_du));
    Vec3f b = normalize_or_zero(cross(n, t));
    if (dot(b, dp_dv) < 0.0f) b = b * -1.0f;
    if (length_squared(t) == 0.0f || length_squared(b) == 0.0f) return false;
    const float inv = 1.0f / float(size);
    step.along_x_t = dot(t, dp_du) * inv;
    step.along_y_t = -dot(t, dp_dv) * inv;  // a row down is -v
    step.along_y_b = -dot(b, dp_dv) * inv;
    return std::isfinite(step.along_x_t) && std::isfinite(step.along_y_t) && std::isfinite(step.along_y_b);
}

/// The texel a UV point lies in, or -1 outside the map.
int texel_at(Vec2f uv, int size) {
    const float x = uv.x * float(size), y = (1.0f - uv.y) * float(size);
    if (!(x >= 0.0f && y >= 0.0f && x < float(size) && y < float(size))) return -1;
    return int(y) * size + int(x);
}

/// Links the texels just inside each side of every seam edge, one pair per texel of its length.
std::vector<std::pair<int, int>> link_seams(const TriangleMesh& mesh, const std::vector<SharedEdge>& edges,
                                           const SurfaceTexels& s, const UvRaster& raster) {
    std::vector<std::pair<int, int>> links;
    const float size = float(s.size);
    for (const SharedEdge& e : edges) {
        if (uv_continuity(mesh, e) != EdgeContinuity::Seam) continue;
        Vec2f a[2], b[2], inward[2];
        bool usable = true;
        for (int k = 0; k < 2; ++k) {
            a[k] = corner_uv(mesh, e.face[k], e.corner_lo[k]);
            b[k] = corner_uv(mesh, e.face[k], e.corner_hi[k]);
            const Vec2f opposite = corner_uv(mesh, e.face[k], 3 - e.corner_lo[k] - e.corner_hi[k]);
            const Vec2f d = b[k] - a[k];
            // Half a texel into the face, perpendicular to the edge, so the point's texel is the face's.
            Vec2f perpendicular{-d.y, d.x};
            if (dot(perpendicular, opposite - a[k]) < 0.0f) perpendicular = perpendicular * -1.0f;
            const float l = length(perpendicular);
            usable = usable && l * size > 1e-6f;
            inward[k] = usable ? perpendicular * (0.5f / (l * size)) : Vec2f{};
        }
        if (!usable) continue;
        const float texels = std::max(length(b[0] - a[0]), length(b[1] - a[1])) * size;
        const int samples = std::max(1, int(std::ceil(texels)));
        for (int i = 0; i < samples; ++i) {
            const float t = (float(i) + 0.5f) / float(samples);
            int ends[2];
            for (int k = 0; k < 2; ++k) {
                const int texel = texel_at(a[k] * (1.0f - t) + b[k] * t + inward[k], s.size);
                ends[k] = texel >= 0 && raster.triangle[std::size_t(texel)] >= 0 ? s.node[std::size_t(texel)] : -1;
            }
            if (ends[0] >= 0 && ends[1] >= 0 && ends[0] != ends[1])
                links.emplace_back(std::min(ends[0], ends[1]), std::max(ends[0], ends[1]));
        }
    }
    std::sort(links.begin(), links.end());
    links.erase(std::unique(links.begin(), links.end()), links.end());
    return links;
}

}  // namespace

SurfaceTexels surface_texels(const TriangleMesh& mesh, const UvRaster& raster) {
    TDF_CHECK(mesh.has_uvs() && raster.size > 0);
    SurfaceTexels s;
    s.size = raster.size;
    s.node.assign(raster.texel_count(), -1);
    for (std::size_t t = 0; t < raster.texel_count(); ++t)
        if (raster.triangle[t] >= 0) {
            s.node[t] = int(s.texels.size());
            s.texels.push_back(std::uint32_t(t));
        }
    // Per face once; a face with no UV area takes the isometry at the mesh's mean scale.
    double area3 = 0, area_uv = 0;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Vec3i& p = mesh.triangles[f];
        area3 += triangle_area(mesh.positions[std::size_t(p[0])], mesh.positions[std::size_t(p[1])],
                               mesh.positions[std::size_t(p[2])]);
        area_uv += 0.5 * std::abs(signed_uv_area2(corner_uv(mesh, int(f), 0), corner_uv(mesh, int(f), 1),
                                                  corner_uv(mesh, int(f), 2)));
    }
    const float mean = area_uv > 0 ? float(std::sqrt(area3 / area_uv)) / float(s.size) : 1.0f / float(s.size);
    std::vector<TexelStep> per_face(mesh.triangles.size());
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        if (!face_step(mesh, int(f), s.size, per_face[f])) per_face[f] = {mean, 0.0f, -mean};
    const std::vector<SharedEdge> edges = shared_edges(mesh);
    const std::vector<int> chart_of_face = uv_charts(mesh, edges);
    s.step.reserve(s.texels.size());
    s.chart.reserve(s.texels.size());
    for (std::uint32_t t : s.texels) {
        const std::size_t face = std::size_t(raster.triangle[t]);
        s.step.push_back(per_face[face]);
        s.chart.push_back(chart_of_face[face]);
    }
    s.seam_links = link_seams(mesh, edges, s, raster);
    return s;
}

}  // namespace tdf
