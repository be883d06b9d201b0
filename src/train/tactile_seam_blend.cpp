#include <tdf/train/tactile_seam_blend.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/tangent_frame.h>
#include <tdf/mesh/uv_seams.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tdf {

namespace {

// Complex arithmetic on UVs: the similarity z -> b0 + (z - a0) q maps an edge a0-a1 onto b0-b1.
Vec2f complex_multiply(Vec2f a, Vec2f b) { return {a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x}; }
Vec2f complex_divide(Vec2f a, Vec2f b) {
    const float d = b.x * b.x + b.y * b.y;
    return {(a.x * b.x + a.y * b.y) / d, (a.y * b.x - a.x * b.y) / d};
}

// The interpolated tangent frame of `face` at the point `t` of the way from corner `lo` to `hi`.
TangentFrame edge_frame(const TriangleMesh& mesh, int face, int lo, int hi, float t) {
    const Vec3i& p = mesh.triangles[std::size_t(face)];
    const Vec3i& tt = mesh.tangent_triangles[std::size_t(face)];
    const Vec4f t_lo = mesh.tangents[std::size_t(tt[lo])], t_hi = mesh.tangents[std::size_t(tt[hi])];
    TangentFrame f;
    f.normal = safe_normalize(mesh.normals[std::size_t(p[lo])] * (1.0f - t) + mesh.normals[std::size_t(p[hi])] * t);
    f.tangent = safe_normalize(t_lo.xyz() * (1.0f - t) + t_hi.xyz() * t);
    f.handedness = t_lo.w < 0.0f ? -1.0f : 1.0f;
    return f;
}

// One side of one seam edge: the segment in this side's UVs and the map onto the other side's.
struct SeamSide {
    int face, other_face;
    int lo, hi, other_lo, other_hi;  // corners
    Vec2f a0, a1, b0, q;             // this side's ends, the other side's start, the similarity factor
};

struct Nearest {
    float distance = std::numeric_limits<float>::max();  // texels
    int side = -1;
    float along = 0.0f;  // 0 at lo, 1 at hi
};

}  // namespace

SeamBlendStats cross_fade_tactile_seams(Image& target, const TexelAtlas& atlas, const TriangleMesh& mesh,
                                        const SurfaceMaterial& material, float band_texels) {
    SeamBlendStats stats;
    if (!(band_texels > 0.0f) || !material.tactile || !mesh.has_uvs() || mesh.tangents.empty()) return stats;
    TDF_CHECK(atlas.has_target_inputs());
    const std::vector<SharedEdge> edges = shared_edges(mesh);
    const std::vector<int> chart = uv_charts(mesh, edges);
    std::vector<SeamSide> sides;
    for (const SharedEdge& e : edges) {
        if (uv_continuity(mesh, e) != EdgeContinuity::Seam) continue;
        ++stats.seam_edges;
        for (int s = 0; s < 2; ++s) {
            SeamSide side{e.face[s], e.face[1 - s], e.corner_lo[s], e.corner_hi[s], e.corner_lo[1 - s],
                          e.corner_hi[1 - s], {}, {}, {}, {}};
            side.a0 = corner_uv(mesh, side.face, side.lo);
            side.a1 = corner_uv(mesh, side.face, side.hi);
            side.b0 = corner_uv(mesh, side.other_face, side.other_lo);
            const Vec2f da = side.a1 - side.a0, db = corner_uv(mesh, side.other_face, side.other_hi) - side.b0;
            if (length_squared(da) < 1e-14f || length_squared(db) < 1e-14f) continue;
            side.q = complex_divide(db, da);
            sides.push_back(side);
        }
    }

    // Each covered texel's nearest seam edge of its own chart within the band (UVs in texels).
    const float size = float(atlas.size);
    std::vector<Nearest> nearest(atlas.texel_count());
    for (std::size_t i = 0; i < sides.size(); ++i) {
        const SeamSide& s = sides[i];
        const Vec2f p0 = s.a0 * size, p1 = s.a1 * size, d = p1 - p0;
        const float len2 = length_squared(d);
        // Texel (x, y) has its centre at u = (x + 0.5) / size, v = 1 - (y + 0.5) / size.
        const int x0 = std::max(0, int(std::floor(std::min(p0.x, p1.x) - band_texels - 0.5f)));
        const int x1 = std::min(atlas.size - 1, int(std::ceil(std::max(p0.x, p1.x) + band_texels)));
        const int y0 = std::max(0, int(std::floor(size - std::max(p0.y, p1.y) - band_texels - 0.5f)));
        const int y1 = std::min(atlas.size - 1, int(std::ceil(size - std::min(p0.y, p1.y) + band_texels)));
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                const std::size_t t = std::size_t(y) * std::size_t(atlas.size) + std::size_t(x);
                const int face = atlas.raster.triangle[t];
                if (face < 0 || chart[std::size_t(face)] != chart[std::size_t(s.face)]) continue;
                const Vec2f c{float(x) + 0.5f, size - (float(y) + 0.5f)};
                const float along = std::clamp(dot(c - p0, d) / len2, 0.0f, 1.0f);
                const float distance = length(c - (p0 + d * along));
                if (distance < band_texels && distance < nearest[t].distance) nearest[t] = {distance, int(i), along};
            }
    }

    std::size_t blended = 0;
    for (const Nearest& n : nearest) blended += n.side >= 0 ? 1 : 0;
    stats.blended_texels = blended;
    parallel_for(atlas.covered_count(), 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = atlas.texels[k];
            const Nearest& n = nearest[t];
            if (n.side < 0) continue;
            const SeamSide& s = sides[std::size_t(n.side)];
            // The other chart's layout continued to this surface point, and its footprint.
            const Vec2f uv_other = s.b0 + complex_multiply(atlas.uvs[k] - s.a0, s.q);
            const Vec2f dx = complex_multiply(Vec2f{1.0f / size, 0.0f}, s.q), dy = complex_multiply(Vec2f{0.0f, -1.0f / size}, s.q);
            const Vec3f other = sample_tactile_layout(material, uv_other, dx, dy);
            // From the other side's tangent frame to this side's, both taken on the seam.
            const TangentFrame from = edge_frame(mesh, s.other_face, s.other_lo, s.other_hi, n.along);
            const TangentFrame to = edge_frame(mesh, s.face, s.lo, s.hi, n.along);
            const Vec3f turned = tbn_transpose_product(to, tbn_product(from, other));
            const float w = 0.5f * (1.0f - n.distance / band_texels);
            float* own = target.data() + 3 * t;
            const Vec3f mine{own[0], own[1], own[2]};  // each texel reads and writes only itself
            const Vec3f mixed = safe_normalize(mine * (1.0f - w) + safe_normalize(turned) * w);
            own[0] = mixed.x, own[1] = mixed.y, own[2] = mixed.z;
        }
    });
    atlas.fill_gutter(target);
    return stats;
}

}  // namespace tdf
