#include <tdf/mesh/triangle_mesh.h>

#include <tdf/core/error.h>
#include <tdf/core/union_find.h>
#include <tdf/mesh/uv_seams.h>

#include <cmath>
#include <map>
#include <tuple>
#include <utility>

namespace tdf {

Bounds3 compute_bounds(const TriangleMesh& mesh) {
    Bounds3 b;
    if (mesh.positions.empty()) return b;
    b.lower = b.upper = mesh.positions[0];
    for (const Vec3f& p : mesh.positions) {
        b.lower = min(b.lower, p);
        b.upper = max(b.upper, p);
    }
    return b;
}

void compute_normals(TriangleMesh& mesh) {
    std::vector<Vec3f> sums(mesh.positions.size(), Vec3f{0, 0, 0});
    for (const Vec3i& t : mesh.triangles) {
        const Vec3f p0 = mesh.positions[std::size_t(t.x)];
        const Vec3f face = cross(mesh.positions[std::size_t(t.y)] - p0, mesh.positions[std::size_t(t.z)] - p0);
        for (int k = 0; k < 3; ++k) sums[std::size_t(t[k])] += face;
    }
    mesh.normals.resize(sums.size());
    for (std::size_t i = 0; i < sums.size(); ++i)
        mesh.normals[i] = length_squared(sums[i]) <= 1e-20f ? Vec3f{0, 0, 1} : safe_normalize(sums[i]);
}

namespace {

// Any unit vector perpendicular to n (Duff et al. 2017 branchless basis).
Vec3f perpendicular(Vec3f n) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    return {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
}

// The reference's clamped determinant (spec 3.3): |D| >= 1e-6, and D = 0 counts as negative.
float clamp_determinant(float d) { return d > 0.0f ? std::max(d, 1e-6f) : std::min(d, -1e-6f); }

// Joins, in `frame_of` (tangent vertex -> the tangent vertex whose frame it uses), the corners of
// faces of the same handedness that meet at a position edge whose two UV corners both differ by
// one translation. Every tangent vertex ends up pointing at the smallest of its group.
void weld_translation_seams(const TriangleMesh& mesh, const std::vector<int>& face_side, std::vector<int>& frame_of) {
    constexpr float kSameShift = 1e-5f;
    for (const SharedEdge& e : shared_edges(mesh)) {
        const int s = e.face[0], t = e.face[1];
        if (face_side[std::size_t(s)] != face_side[std::size_t(t)]) continue;
        const Vec2f shift_lo = corner_uv(mesh, t, e.corner_lo[1]) - corner_uv(mesh, s, e.corner_lo[0]);
        const Vec2f shift_hi = corner_uv(mesh, t, e.corner_hi[1]) - corner_uv(mesh, s, e.corner_hi[0]);
        const bool moved = std::fabs(shift_lo.x) + std::fabs(shift_lo.y) > kSameShift;
        if (!moved || std::fabs(shift_lo.x - shift_hi.x) + std::fabs(shift_lo.y - shift_hi.y) > kSameShift) continue;
        for (const auto& [cs, ct] : {std::pair{e.corner_lo[0], e.corner_lo[1]}, std::pair{e.corner_hi[0], e.corner_hi[1]}}) {
            const int a = find_root(frame_of, mesh.tangent_triangles[std::size_t(s)][cs]);
            const int b = find_root(frame_of, mesh.tangent_triangles[std::size_t(t)][ct]);
            frame_of[std::size_t(std::max(a, b))] = std::min(a, b);
        }
    }
    for (std::size_t v = 0; v < frame_of.size(); ++v) frame_of[v] = find_root(frame_of, int(v));
}

}  // namespace

void compute_tangents(TriangleMesh& mesh, TangentMode mode) {
    const std::size_t face_count = mesh.triangles.size();
    mesh.tangent_triangles.assign(face_count, Vec3i{});
    if (!mesh.has_uvs()) {
        // No UVs: a tangent frame still exists for tactile maps laid by other means.
        mesh.tangents.resize(mesh.positions.size());
        for (std::size_t v = 0; v < mesh.positions.size(); ++v)
            mesh.tangents[v] = Vec4f(perpendicular(mesh.normals[v]), 1.0f);
        mesh.tangent_triangles = mesh.triangles;
        return;
    }

    // Per face: dP/du and the handedness of its UV layout.
    std::vector<Vec3f> face_tangent(face_count);
    std::vector<int> face_side(face_count);
    for (std::size_t f = 0; f < face_count; ++f) {
        const Vec3i& t = mesh.triangles[f];
        const Vec3i& ti = mesh.uv_triangles[f];
        const Vec3f p0 = mesh.positions[std::size_t(t.x)];
        const Vec3f e1 = mesh.positions[std::size_t(t.y)] - p0;
        const Vec3f e2 = mesh.positions[std::size_t(t.z)] - p0;
        // Reference UV convention v' = 1 - v (spec 1.2): the tangent formula is written in it.
        const Vec2f t0 = mesh.uvs[std::size_t(ti.x)], t1 = mesh.uvs[std::size_t(ti.y)], t2 = mesh.uvs[std::size_t(ti.z)];
        const float du1 = t1.x - t0.x, dv1 = -(t1.y - t0.y);
        const float du2 = t2.x - t0.x, dv2 = -(t2.y - t0.y);
        const float d = clamp_determinant(du1 * dv2 - dv1 * du2);
        face_tangent[f] = (e1 * dv2 - e2 * dv1) / d;                  // dP/du
        const Vec3f face_bitangent_down = (e2 * du1 - e1 * du2) / d;  // dP/dv'
        // Handedness: +1 when N x T points toward increasing OBJ v (= decreasing v').
        face_side[f] = dot(cross(cross(e1, e2), face_tangent[f]), -face_bitangent_down) >= 0.0f ? 1 : -1;
    }

    // Tangent vertices: per position (Reference) or, like MikkTSpace, per (position, uv,
    // handedness) (Handed): charts that meet at a seam keep their own tangent, and so do the two
    // sides of a mirror line whose corners share their UVs (a symmetric layout), which would
    // otherwise average opposite tangents away.
    std::vector<int> position_of;  // tangent vertex -> position index
    if (mode == TangentMode::Reference) {
        mesh.tangent_triangles = mesh.triangles;
        position_of.resize(mesh.positions.size());
        for (std::size_t v = 0; v < position_of.size(); ++v) position_of[v] = int(v);
    } else {
        std::map<std::tuple<int, int, int>, int> corner_ids;
        for (std::size_t f = 0; f < face_count; ++f)
            for (int k = 0; k < 3; ++k) {
                const auto key = std::make_tuple(mesh.triangles[f][k], mesh.uv_triangles[f][k], face_side[f]);
                auto [it, inserted] = corner_ids.emplace(key, int(position_of.size()));
                if (inserted) position_of.push_back(std::get<0>(key));
                mesh.tangent_triangles[f][k] = it->second;
            }
    }

    const std::size_t n = position_of.size();
    // Seams across which the UV layout only moves (a sphere's u = 0 / u = 1 meridian, a tiled
    // chart) continue the same tangent space: both sides share one frame there (the sum of all
    // their faces), so a map that continues across the seam shades without a crease. Seams between
    // charts turned or scaled against each other keep their own frames.
    std::vector<int> frame_of(n);
    for (std::size_t v = 0; v < n; ++v) frame_of[v] = int(v);
    if (mode == TangentMode::Handed) weld_translation_seams(mesh, face_side, frame_of);
    std::vector<Vec3f> tangent_sum(n, Vec3f{0, 0, 0});
    std::vector<float> handedness_sum(n, 0.0f);
    std::vector<int> face_counts(n, 0);
    for (std::size_t f = 0; f < face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const std::size_t tv = std::size_t(frame_of[std::size_t(mesh.tangent_triangles[f][k])]);
            tangent_sum[tv] += face_tangent[f];
            handedness_sum[tv] += float(face_side[f]);
            face_counts[tv] += 1;
        }
    mesh.tangents.resize(n);
    for (std::size_t v = 0; v < n; ++v) {
        const Vec3f normal = mesh.normals[std::size_t(position_of[v])];
        const std::size_t frame = std::size_t(frame_of[v]);
        Vec3f tangent = tangent_sum[frame] / float(std::max(face_counts[frame], 1));
        tangent = normalize_or_zero(tangent);
        tangent = normalize_or_zero(tangent - normal * dot(tangent, normal));
        if (mode == TangentMode::Handed && length_squared(tangent) == 0.0f) tangent = perpendicular(normal);
        const float w = (mode == TangentMode::Reference || handedness_sum[frame] >= 0.0f) ? 1.0f : -1.0f;
        mesh.tangents[v] = Vec4f(tangent, w);
    }
}

void normalize_mesh(TriangleMesh& mesh, float bound) {
    const Bounds3 b = compute_bounds(mesh);
    const Vec3f e = b.extent();
    const float largest = std::max(e.x, std::max(e.y, e.z));
    if (!(largest > 0.0f)) throw_error("{}: cannot normalise a mesh with zero extent", mesh.source_path);
    const float scale = 2.0f * bound / largest;
    const Vec3f c = b.center();
    for (Vec3f& p : mesh.positions) p = (p - c) * scale;
}

std::size_t validate_mesh(const TriangleMesh& mesh, const std::string& source) {
    if (mesh.positions.empty()) throw_error("{}: the mesh has no vertices", source);
    if (mesh.triangles.empty()) throw_error("{}: the mesh has no faces", source);
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
        if (!is_finite(mesh.positions[i]))
            throw_error("{}: vertex {} has a non-finite coordinate ({}, {}, {})", source, i + 1,
                        mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z);
    for (std::size_t i = 0; i < mesh.uvs.size(); ++i)
        if (!std::isfinite(mesh.uvs[i].x) || !std::isfinite(mesh.uvs[i].y))
            throw_error("{}: texture coordinate {} is not finite", source, i + 1);
    for (std::size_t i = 0; i < mesh.colors.size(); ++i)
        if (!is_finite(mesh.colors[i])) throw_error("{}: vertex colour {} is not finite", source, i + 1);
    if (!mesh.colors.empty() && mesh.colors.size() != mesh.positions.size())
        throw_error("{}: {} vertex colours for {} vertices", source, mesh.colors.size(), mesh.positions.size());
    if (!mesh.uv_triangles.empty() && mesh.uv_triangles.size() != mesh.triangles.size())
        throw_error("{}: {} UV faces for {} faces", source, mesh.uv_triangles.size(), mesh.triangles.size());
    if (!mesh.face_group.empty() && mesh.face_group.size() != mesh.triangles.size())
        throw_error(
            "{}: {} face group entries for {} faces", source, mesh.face_group.size(), mesh.triangles.size());
    if (mesh.face_group.empty() != mesh.face_groups.empty())
        throw_error("{}: face groups are half set ({} groups, {} face entries)",
                    source,
                    mesh.face_groups.size(),
                    mesh.face_group.size());
    for (std::size_t f = 0; f < mesh.face_group.size(); ++f)
        if (mesh.face_group[f] < 0 || std::size_t(mesh.face_group[f]) >= mesh.face_groups.size())
            throw_error("{}: face {} is in group {} but the mesh has {} groups",
                        source,
                        f + 1,
                        mesh.face_group[f],
                        mesh.face_groups.size());
    const auto n = int(mesh.positions.size());
    const auto nt = int(mesh.uvs.size());
    std::size_t degenerate = 0;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Vec3i& t = mesh.triangles[f];
        for (int k = 0; k < 3; ++k)
            if (t[k] < 0 || t[k] >= n)
                throw_error("{}: face {} uses vertex {} but the mesh has {} vertices", source, f + 1, t[k] + 1, n);
        if (mesh.has_uvs())
            for (int k = 0; k < 3; ++k)
                if (mesh.uv_triangles[f][k] < 0 || mesh.uv_triangles[f][k] >= nt)
                    throw_error("{}: face {} uses texture coordinate {} but the mesh has {}", source, f + 1,
                                mesh.uv_triangles[f][k] + 1, nt);
        const Vec3f p0 = mesh.positions[std::size_t(t.x)];
        const Vec3f c = cross(mesh.positions[std::size_t(t.y)] - p0, mesh.positions[std::size_t(t.z)] - p0);
        if (!(length_squared(c) > 0.0f)) ++degenerate;
    }
    if (degenerate == mesh.triangles.size())
        throw_error("{}: all {} faces have zero area", source, degenerate);
    return degenerate;
}

}  // namespace tdf
