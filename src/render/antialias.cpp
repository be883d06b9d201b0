#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/render/antialias.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <unordered_map>
#include <utility>

namespace tdf {

namespace {

inline std::uint64_t edge_key(int a, int b) {
    const auto lo = std::uint64_t(std::uint32_t(std::min(a, b))),
               hi = std::uint64_t(std::uint32_t(std::max(a, b)));
    return lo | (hi << 32);
}

// Sign bits equal (so -0 and +0 differ, as in the GPU code this mirrors).
inline bool same_sign(float a, float b) { return std::signbit(a) == std::signbit(b); }
// n0 / d0 > n1 / d1 without dividing.
inline bool rational_gt(float n0, float n1, float d0, float d1) {
    return (n0 * d1 > n1 * d0) == same_sign(d0, d1);
}
inline int max_idx3(float n0, float n1, float n2, float d0, float d1, float d2) {
    const bool g10 = rational_gt(n1, n0, d1, d0);
    const bool g20 = rational_gt(n2, n0, d2, d0);
    const bool g21 = rational_gt(n2, n1, d2, d1);
    if (g20 && g21) return 2;
    if (g10) return 1;
    return 0;
}

}  // namespace

EdgeTopology::EdgeTopology(const std::vector<Vec3i>& triangles, std::size_t vertex_count) {
    // Up to two distinct opposite vertices per edge, first come first kept (triangle order).
    std::unordered_map<std::uint64_t, std::pair<int, int>> edges;
    edges.reserve(triangles.size() * 2);
    auto valid = [&](const Vec3i& t) {
        const auto n = int(vertex_count);
        return t.x >= 0 && t.y >= 0 && t.z >= 0 && t.x < n && t.y < n && t.z < n && t.x != t.y &&
               t.y != t.z && t.z != t.x;
    };
    auto insert = [&](int a, int b, int opposite) {
        auto [it, fresh] = edges.try_emplace(edge_key(a, b), opposite, -1);
        if (!fresh && it->second.first != opposite && it->second.second < 0) it->second.second = opposite;
    };
    for (const Vec3i& t : triangles) {
        if (!valid(t)) continue;
        insert(t.y, t.z, t.x);
        insert(t.z, t.x, t.y);
        insert(t.x, t.y, t.z);
    }
    auto find = [&](int a, int b, int self) {
        const auto it = edges.find(edge_key(a, b));
        if (it == edges.end()) return -1;
        if (it->second.first == self) return it->second.second;
        if (it->second.second == self) return it->second.first;
        return -1;
    };
    m_opposite.resize(triangles.size(), Vec3i{-1, -1, -1});
    for (std::size_t k = 0; k < triangles.size(); ++k) {
        const Vec3i& t = triangles[k];
        if (!valid(t)) continue;
        m_opposite[k] = {find(t.z, t.y, t.x), find(t.x, t.z, t.y), find(t.y, t.x, t.z)};
    }
}

void AntialiasPlan::analyze(int width, int height, const int* triangle, const float* depth,
                            const std::vector<Vec4f>& clip, const std::vector<Vec3i>& triangles,
                            const EdgeTopology& topology) {
    TDF_CHECK_EQ(topology.triangle_count(), triangles.size());
    m_width = width;
    m_height = height;
    const std::size_t n = std::size_t(width) * std::size_t(height);
    m_alpha_right.assign(n, 0.f);
    m_alpha_down.assign(n, 0.f);
    m_touched_rows.assign(std::size_t(height), 0);
    const float xh = 0.5f * float(width), yh = 0.5f * float(height);
    const int n_triangles = int(triangles.size());

    // alpha of the pair (x, y) -> neighbour (right when down == 0, below otherwise), 0 if none.
    auto pair_alpha = [&](int x, int y, int down) -> float {
        const std::size_t p0 = std::size_t(y) * std::size_t(width) + std::size_t(x);
        const std::size_t p1 = p0 + (down ? std::size_t(width) : 1);
        const int tri0 = triangle[p0], tri1 = triangle[p1];
        if (tri0 == tri1) return 0.f;
        int tri = tri0 >= 0 ? tri0 : tri1;
        if (tri0 >= 0 && tri1 >= 0) tri = depth[p0] < depth[p1] ? tri0 : tri1;
        int px = x, py = y;
        if (tri == tri1) {  // measure from the neighbour's centre
            px += 1 - down;
            py += down;
        }
        if (tri < 0 || tri >= n_triangles) return 0.f;
        const Vec3i& vi = triangles[std::size_t(tri)];
        const Vec3i& op = topology.opposite(tri);
        const Vec4f& c0 = clip[std::size_t(vi.x)];
        const Vec4f& c1 = clip[std::size_t(vi.y)];
        const Vec4f& c2 = clip[std::size_t(vi.z)];
        const Vec4f& o0 = op.x < 0 ? c0 : clip[std::size_t(op.x)];
        const Vec4f& o1 = op.y < 0 ? c1 : clip[std::size_t(op.y)];
        const Vec4f& o2 = op.z < 0 ? c2 : clip[std::size_t(op.z)];
        // Pixel-space positions relative to the pixel centre.
        const float fx = float(px) + 0.5f - xh, fy = float(py) + 0.5f - yh;
        auto sx = [&](const Vec4f& c) { return c.x * (1.f / c.w) * xh - fx; };
        auto sy = [&](const Vec4f& c) { return c.y * (1.f / c.w) * yh - fy; };
        float x0 = sx(c0), y0 = sy(c0), x1 = sx(c1), y1 = sy(c1), x2 = sx(c2), y2 = sy(c2);
        const float ox0 = sx(o0), oy0 = sy(o0), ox1 = sx(o1), oy1 = sy(o1), ox2 = sx(o2), oy2 = sy(o2);
        // An edge is a silhouette when the wing triangle (edge + opposite vertex) has the same
        // screen orientation as the triangle itself, i.e. folds onto the same side.
        const float bb = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
        const float a0 = (x1 - ox0) * (y2 - oy0) - (x2 - ox0) * (y1 - oy0);
        const float a1 = (x2 - ox1) * (y0 - oy1) - (x0 - ox1) * (y2 - oy1);
        const float a2 = (x0 - ox2) * (y1 - oy2) - (x1 - ox2) * (y0 - oy2);
        if (!same_sign(a0, bb) && !same_sign(a1, bb) && !same_sign(a2, bb)) return 0.f;
        if (down) {  // vertical pairs: the same test with x and y exchanged
            std::swap(x0, y0);
            std::swap(x1, y1);
            std::swap(x2, y2);
        }
        float dx0 = x2 - x1, dx1 = x0 - x2, dx2 = x1 - x0;
        float dy0 = y2 - y1, dy1 = y0 - y2, dy2 = y1 - y0;
        const float ds = tri == tri0 ? 1.f : -1.f;
        // Signed crossing of each edge with the x axis (the segment between the centres),
        // as numerator / dy; edges that do not cross the axis are ruled out.
        float d0 = ds * (x1 * dy0 - y1 * dx0);
        float d1 = ds * (x2 * dy1 - y2 * dx1);
        float d2 = ds * (x0 * dy2 - y0 * dx2);
        if (same_sign(y1, y2)) d0 = -FLT_MAX, dy0 = 1.f;
        if (same_sign(y2, y0)) d1 = -FLT_MAX, dy1 = 1.f;
        if (same_sign(y0, y1)) d2 = -FLT_MAX, dy2 = 1.f;
        const int di = max_idx3(d0, d1, d2, dy0, dy1, dy2);
        float dc = -FLT_MAX;
        if (di == 0 && same_sign(a0, bb) && std::fabs(dy0) >= std::fabs(dx0)) dc = d0 / dy0;
        if (di == 1 && same_sign(a1, bb) && std::fabs(dy1) >= std::fabs(dx1)) dc = d1 / dy1;
        if (di == 2 && same_sign(a2, bb) && std::fabs(dy2) >= std::fabs(dx2)) dc = d2 / dy2;
        constexpr float kEps = 0.0625f;  // up to 1/16 pixel of inaccuracy tolerated
        if (!(dc > -kEps && dc < 1.f + kEps)) return 0.f;
        dc = std::min(std::max(dc, 0.f), 1.f);
        return ds * (0.5f - dc);
    };

    parallel_for(std::size_t(height), 8, [&](std::size_t yb, std::size_t ye) {
        for (std::size_t yy = yb; yy < ye; ++yy) {
            const int y = int(yy);
            bool touched = false;
            for (int x = 0; x < width; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
                if (x + 1 < width) m_alpha_right[i] = pair_alpha(x, y, 0);
                if (y + 1 < height) m_alpha_down[i] = pair_alpha(x, y, 1);
                touched = touched || m_alpha_right[i] != 0.f || m_alpha_down[i] != 0.f;
            }
            if (touched) m_touched_rows[yy] = 1;
        }
    });
}

std::size_t AntialiasPlan::blended_pairs() const {
    std::size_t count = 0;
    for (std::size_t i = 0; i < m_alpha_right.size(); ++i)
        count += std::size_t(m_alpha_right[i] != 0.f) + std::size_t(m_alpha_down[i] != 0.f);
    return count;
}

void AntialiasPlan::apply(Image& image) const {
    TDF_CHECK(image.width() == m_width && image.height() == m_height);
    const int w = m_width, h = m_height, c = image.channels();
    const Image input = image;
    const float* in = input.data();
    float* out = image.data();
    // Gather per output pixel in a fixed order (own right pair, own down pair, left neighbour's
    // pair, upper neighbour's pair): deterministic, unlike the GPU's atomic adds.
    parallel_for(std::size_t(h), 8, [&](std::size_t yb, std::size_t ye) {
        for (std::size_t yy = yb; yy < ye; ++yy) {
            const int y = int(yy);
            const bool near = m_touched_rows[yy] || (y > 0 && m_touched_rows[yy - 1]);
            if (!near) continue;
            for (int x = 0; x < w; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
                auto add = [&](float alpha, std::size_t from0, std::size_t from1) {
                    for (int k = 0; k < c; ++k)
                        out[i * std::size_t(c) + std::size_t(k)] +=
                            alpha * (in[from1 * std::size_t(c) + std::size_t(k)] -
                                     in[from0 * std::size_t(c) + std::size_t(k)]);
                };
                if (m_alpha_right[i] > 0.f) add(m_alpha_right[i], i, i + 1);
                if (m_alpha_down[i] > 0.f) add(m_alpha_down[i], i, i + std::size_t(w));
                if (x > 0 && m_alpha_right[i - 1] < 0.f) add(m_alpha_right[i - 1], i - 1, i);
                if (y > 0 && m_alpha_down[i - std::size_t(w)] < 0.f)
                    add(m_alpha_down[i - std::size_t(w)], i - std::size_t(w), i);
            }
        }
    });
}

}  // namespace tdf
