#include <tdf/mesh/uv_seams.h>

#include <tdf/core/union_find.h>

#include <algorithm>
#include <numeric>
#include <tuple>

namespace tdf {

std::vector<SharedEdge> shared_edges(const TriangleMesh& mesh) {
    struct Side {
        int lo, hi, face, corner_lo, corner_hi;
    };
    std::vector<Side> sides;
    sides.reserve(3 * mesh.triangles.size());
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            int ka = k, kb = (k + 1) % 3;
            const int a = mesh.triangles[f][ka], b = mesh.triangles[f][kb];
            if (a == b) continue;
            if (a > b) std::swap(ka, kb);
            sides.push_back({std::min(a, b), std::max(a, b), int(f), ka, kb});
        }
    std::sort(sides.begin(), sides.end(), [](const Side& x, const Side& y) {
        return std::tie(x.lo, x.hi, x.face) < std::tie(y.lo, y.hi, y.face);
    });
    std::vector<SharedEdge> edges;
    for (std::size_t begin = 0; begin < sides.size();) {
        std::size_t end = begin + 1;
        while (end < sides.size() && sides[end].lo == sides[begin].lo && sides[end].hi == sides[begin].hi) ++end;
        for (std::size_t i = begin; i < end; ++i)
            for (std::size_t j = i + 1; j < end; ++j)
                edges.push_back({{sides[i].face, sides[j].face},
                                 {sides[i].corner_lo, sides[j].corner_lo},
                                 {sides[i].corner_hi, sides[j].corner_hi}});
        begin = end;
    }
    return edges;
}

EdgeContinuity uv_continuity(const TriangleMesh& mesh, const SharedEdge& e) {
    if (e.face[0] == e.face[1]) return EdgeContinuity::Same;
    if (!mesh.has_uvs()) return EdgeContinuity::Continuous;
    const auto same = [&](int c0, int c1) {
        const Vec2f a = corner_uv(mesh, e.face[0], c0), b = corner_uv(mesh, e.face[1], c1);
        return a.x == b.x && a.y == b.y;
    };
    const bool lo = same(e.corner_lo[0], e.corner_lo[1]), hi = same(e.corner_hi[0], e.corner_hi[1]);
    return lo && hi ? EdgeContinuity::Continuous : lo || hi ? EdgeContinuity::Cone : EdgeContinuity::Seam;
}

std::vector<int> uv_charts(const TriangleMesh& mesh, const std::vector<SharedEdge>& edges) {
    std::vector<int> parent(mesh.triangles.size());
    std::iota(parent.begin(), parent.end(), 0);
    for (const SharedEdge& e : edges)
        if (uv_continuity(mesh, e) == EdgeContinuity::Continuous) {
            const int a = find_root(parent, e.face[0]), b = find_root(parent, e.face[1]);
            parent[std::size_t(std::max(a, b))] = std::min(a, b);
        }
    std::vector<int> chart(mesh.triangles.size(), -1), number(mesh.triangles.size(), -1);
    int charts = 0;
    for (std::size_t f = 0; f < chart.size(); ++f) {
        const int r = find_root(parent, int(f));
        if (number[std::size_t(r)] < 0) number[std::size_t(r)] = charts++;
        chart[f] = number[std::size_t(r)];
    }
    return chart;
}

}  // namespace tdf
