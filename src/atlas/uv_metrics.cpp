#include <tdf/atlas/uv_metrics.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tdf {

namespace {

struct D3 {
    double x, y, z;
};
D3 to_d3(Vec3f v) { return {v.x, v.y, v.z}; }
D3 sub(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot3(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

double corner_angle(D3 a, D3 b, D3 c) {  // angle at a
    const D3 u = sub(b, a), v = sub(c, a);
    const double denominator = std::sqrt(dot3(u, u) * dot3(v, v));
    if (!(denominator > 0.0)) return 0.0;
    return std::acos(std::clamp(dot3(u, v) / denominator, -1.0, 1.0));
}

}  // namespace

double triangle_area(Vec3f a, Vec3f b, Vec3f c) {
    const D3 u = sub(to_d3(b), to_d3(a)), v = sub(to_d3(c), to_d3(a));
    const D3 n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
    return 0.5 * std::sqrt(dot3(n, n));
}

double l2_stretch_squared(const std::array<Vec3f, 3>& q, const std::array<Vec2f, 3>& p) {
    const double area2 = signed_uv_area2(p[0], p[1], p[2]);
    if (area2 == 0.0 || !std::isfinite(area2)) return std::numeric_limits<double>::infinity();
    const double s0 = p[0].x, s1 = p[1].x, s2 = p[2].x, t0 = p[0].y, t1 = p[1].y, t2 = p[2].y;
    const D3 q0 = to_d3(q[0]), q1 = to_d3(q[1]), q2 = to_d3(q[2]);
    const auto combine = [&](double w0, double w1, double w2) {
        return D3{(q0.x * w0 + q1.x * w1 + q2.x * w2) / area2,
                  (q0.y * w0 + q1.y * w1 + q2.y * w2) / area2,
                  (q0.z * w0 + q1.z * w1 + q2.z * w2) / area2};
    };
    const D3 ds = combine(t1 - t2, t2 - t0, t0 - t1);  // dq/du
    const D3 dt = combine(s2 - s1, s0 - s2, s1 - s0);  // dq/dv
    return 0.5 * (dot3(ds, ds) + dot3(dt, dt));
}

AngleDistortion angle_distortion(const std::array<Vec3f, 3>& q, const std::array<Vec2f, 3>& p) {
    AngleDistortion result;
    for (int k = 0; k < 3; ++k) {
        const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        const double a3 =
            corner_angle(to_d3(q[std::size_t(k)]), to_d3(q[std::size_t(k1)]), to_d3(q[std::size_t(k2)]));
        const D3 a{p[std::size_t(k)].x, p[std::size_t(k)].y, 0},
            b{p[std::size_t(k1)].x, p[std::size_t(k1)].y, 0},
            c{p[std::size_t(k2)].x, p[std::size_t(k2)].y, 0};
        const double d = std::abs(corner_angle(a, b, c) - a3) * (180.0 / 3.14159265358979323846);
        result.max = std::max(result.max, d);
        result.sum += d;
    }
    return result;
}

bool triangle_touches_box(const double (&xs)[3], const double (&ys)[3], double x0, double y0, double x1,
                          double y1) {
    if (std::max({xs[0], xs[1], xs[2]}) < x0 || std::min({xs[0], xs[1], xs[2]}) > x1 ||
        std::max({ys[0], ys[1], ys[2]}) < y0 || std::min({ys[0], ys[1], ys[2]}) > y1)
        return false;
    const double corner_x[4] = {x0, x1, x0, x1}, corner_y[4] = {y0, y0, y1, y1};
    for (int k = 0; k < 3; ++k) {
        const int k1 = (k + 1) % 3;
        const double nx = ys[k] - ys[k1], ny = xs[k1] - xs[k];  // a normal of edge k
        if (nx == 0.0 && ny == 0.0) continue;
        double tri_lo = 1e300, tri_hi = -1e300, box_lo = 1e300, box_hi = -1e300;
        for (int j = 0; j < 3; ++j) {
            const double d = xs[j] * nx + ys[j] * ny;
            tri_lo = std::min(tri_lo, d);
            tri_hi = std::max(tri_hi, d);
        }
        for (int j = 0; j < 4; ++j) {
            const double d = corner_x[j] * nx + corner_y[j] * ny;
            box_lo = std::min(box_lo, d);
            box_hi = std::max(box_hi, d);
        }
        if (tri_hi < box_lo || box_hi < tri_lo) return false;
    }
    return true;
}

std::vector<Vec2f> convex_hull(std::vector<Vec2f> points) {
    std::sort(points.begin(), points.end(), [](Vec2f a, Vec2f b) {
        return a.x < b.x || (a.x == b.x && a.y < b.y);
    });
    points.erase(
        std::unique(points.begin(), points.end(), [](Vec2f a, Vec2f b) { return a.x == b.x && a.y == b.y; }),
        points.end());
    if (points.size() < 3) return points;
    std::vector<Vec2f> hull(2 * points.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        while (k >= 2 && signed_uv_area2(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
        hull[k++] = points[i];
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i > 0; --i) {
        while (k >= lower && signed_uv_area2(hull[k - 2], hull[k - 1], points[i - 1]) <= 0) --k;
        hull[k++] = points[i - 1];
    }
    hull.resize(k - 1);
    return hull;
}

double polygon_area(const std::vector<Vec2f>& polygon) {
    double twice = 0;
    for (std::size_t i = 0; i < polygon.size(); ++i) {
        const Vec2f a = polygon[i], b = polygon[(i + 1) % polygon.size()];
        twice += double(a.x) * b.y - double(b.x) * a.y;
    }
    return 0.5 * twice;
}

namespace {

struct UvTriangle {
    double x[3], y[3];
    double min_x, min_y, max_x, max_y;
};

// True when the interiors of a and b overlap (no separating axis among the 6 edge normals).
bool interiors_overlap(const UvTriangle& a, const UvTriangle& b, double tolerance) {
    const double size =
        std::max({a.max_x - a.min_x, a.max_y - a.min_y, b.max_x - b.min_x, b.max_y - b.min_y});
    for (const UvTriangle* t : {&a, &b})
        for (int k = 0; k < 3; ++k) {
            const int k1 = (k + 1) % 3;
            const double nx = t->y[k1] - t->y[k], ny = t->x[k] - t->x[k1];
            const double norm = std::sqrt(nx * nx + ny * ny);
            if (!(norm > 0.0)) continue;
            double a_lo = 1e300, a_hi = -1e300, b_lo = 1e300, b_hi = -1e300;
            for (int j = 0; j < 3; ++j) {
                const double pa = a.x[j] * nx + a.y[j] * ny, pb = b.x[j] * nx + b.y[j] * ny;
                a_lo = std::min(a_lo, pa);
                a_hi = std::max(a_hi, pa);
                b_lo = std::min(b_lo, pb);
                b_hi = std::max(b_hi, pb);
            }
            if (std::min(a_hi, b_hi) - std::max(a_lo, b_lo) <= tolerance * size * norm) return false;
        }
    return true;
}

}  // namespace

std::size_t count_overlapping_pairs(const std::vector<Vec2f>& uvs, const std::vector<Vec3i>& triangles,
                                    bool stop_at_first, double tolerance) {
    std::vector<UvTriangle> tris;
    tris.reserve(triangles.size());
    double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
    for (const Vec3i& t : triangles) {
        UvTriangle u{};
        bool finite = true;
        for (int k = 0; k < 3; ++k) {
            const Vec2f p = uvs[std::size_t(t[k])];
            finite = finite && std::isfinite(p.x) && std::isfinite(p.y);
            u.x[k] = p.x;
            u.y[k] = p.y;
        }
        if (!finite) continue;
        const double area2 = (u.x[1] - u.x[0]) * (u.y[2] - u.y[0]) - (u.y[1] - u.y[0]) * (u.x[2] - u.x[0]);
        if (area2 == 0.0) continue;
        u.min_x = std::min({u.x[0], u.x[1], u.x[2]});
        u.max_x = std::max({u.x[0], u.x[1], u.x[2]});
        u.min_y = std::min({u.y[0], u.y[1], u.y[2]});
        u.max_y = std::max({u.y[0], u.y[1], u.y[2]});
        lo_x = std::min(lo_x, u.min_x);
        lo_y = std::min(lo_y, u.min_y);
        hi_x = std::max(hi_x, u.max_x);
        hi_y = std::max(hi_y, u.max_y);
        tris.push_back(u);
    }
    if (tris.size() < 2) return 0;
    const int grid = std::clamp(int(std::ceil(std::sqrt(double(tris.size())))), 1, 1024);
    const double cell_x = std::max(hi_x - lo_x, 1e-30) / grid, cell_y = std::max(hi_y - lo_y, 1e-30) / grid;
    const auto cell_of = [&](double v, double lo, double cell) {
        return std::clamp(int((v - lo) / cell), 0, grid - 1);
    };
    // Per-cell triangle lists (counting sort of the (cell, triangle) entries).
    const auto for_each_cell = [&](const UvTriangle& u, auto&& visit) {
        for (int cy = cell_of(u.min_y, lo_y, cell_y); cy <= cell_of(u.max_y, lo_y, cell_y); ++cy)
            for (int cx = cell_of(u.min_x, lo_x, cell_x); cx <= cell_of(u.max_x, lo_x, cell_x); ++cx)
                visit(std::size_t(cy) * std::size_t(grid) + std::size_t(cx));
    };
    std::vector<int> start(std::size_t(grid) * std::size_t(grid) + 1, 0);
    for (const UvTriangle& u : tris) for_each_cell(u, [&](std::size_t c) { ++start[c + 1]; });
    for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
    std::vector<int> entries(std::size_t(start.back()));
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < tris.size(); ++i)
        for_each_cell(tris[i], [&](std::size_t c) { entries[std::size_t(fill[c]++)] = int(i); });

    std::size_t count = 0;
    for (int cy = 0; cy < grid; ++cy)
        for (int cx = 0; cx < grid; ++cx) {
            const std::size_t c = std::size_t(cy) * std::size_t(grid) + std::size_t(cx);
            for (int e = start[c]; e < start[c + 1]; ++e)
                for (int g = e + 1; g < start[c + 1]; ++g) {
                    const UvTriangle& a = tris[std::size_t(entries[std::size_t(e)])];
                    const UvTriangle& b = tris[std::size_t(entries[std::size_t(g)])];
                    if (a.max_x < b.min_x || b.max_x < a.min_x || a.max_y < b.min_y || b.max_y < a.min_y)
                        continue;
                    // Test each pair once: in the cell holding the low corner of the bounding-box overlap.
                    if (cell_of(std::max(a.min_x, b.min_x), lo_x, cell_x) != cx ||
                        cell_of(std::max(a.min_y, b.min_y), lo_y, cell_y) != cy)
                        continue;
                    if (interiors_overlap(a, b, tolerance)) {
                        ++count;
                        if (stop_at_first) return count;
                    }
                }
        }
    return count;
}

}  // namespace tdf
