#include <tdf/atlas/uv_metrics.h>
#include <tdf/atlas/uv_raster.h>
#include <tdf/core/error.h>
#include <tdf/core/image_ops.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

struct Point {
    double x, y;
};

// Twice the signed area of (a, b, p) in texel coordinates (x right, y down).
double edge_function(Point a, Point b, Point p) {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Top-left rule for a triangle with positive edge functions inside: a centre exactly on an edge
// is kept only for "top" or "left" edges, so two triangles sharing the edge never both claim it.
bool owns_edge(Point a, Point b) {
    const double dy = b.y - a.y, dx = b.x - a.x;
    return dy < 0.0 || (dy == 0.0 && dx > 0.0);
}

}  // namespace

std::size_t UvRaster::covered_count() const {
    return std::size_t(std::count_if(triangle.begin(), triangle.end(), [](int t) { return t >= 0; }));
}

UvRaster rasterize_uv(const TriangleMesh& mesh, int size) {
    if (!mesh.has_uvs())
        throw_error("{}: cannot rasterize the UV layout of a mesh without UVs", mesh.source_path);
    if (size < 1 || size > 16384) throw_error("UV raster size {} is out of range [1, 16384]", size);
    UvRaster raster;
    raster.size = size;
    const std::size_t count = std::size_t(size) * std::size_t(size);
    raster.triangle.assign(count, -1);
    raster.barycentric.assign(count, Vec3f{0, 0, 0});
    const double s = double(size);
    for (std::size_t f = 0; f < mesh.uv_triangles.size(); ++f) {
        Point p[3];
        for (int k = 0; k < 3; ++k) {
            const Vec2f uv = mesh.uvs[std::size_t(mesh.uv_triangles[f][k])];
            p[k] = {double(uv.x) * s, (1.0 - double(uv.y)) * s};
        }
        // Visit corners so that the area is positive; `order` maps back to the face's corners.
        int order[3] = {0, 1, 2};
        double area = edge_function(p[0], p[1], p[2]);
        if (area < 0.0) {
            std::swap(order[1], order[2]);
            area = -area;
        }
        if (!(area > 0.0)) continue;  // zero-area (or NaN) UV triangle: covers no centre
        const Point a = p[order[0]], b = p[order[1]], c = p[order[2]];
        const bool own_bc = owns_edge(b, c), own_ca = owns_edge(c, a), own_ab = owns_edge(a, b);
        const double min_x = std::min({a.x, b.x, c.x}), max_x = std::max({a.x, b.x, c.x});
        const double min_y = std::min({a.y, b.y, c.y}), max_y = std::max({a.y, b.y, c.y});
        // Centres j + 0.5 in [min_x, max_x].
        const int j0 = std::max(0, int(std::ceil(min_x - 0.5)));
        const int j1 = std::min(size - 1, int(std::floor(max_x - 0.5)));
        const int i0 = std::max(0, int(std::ceil(min_y - 0.5)));
        const int i1 = std::min(size - 1, int(std::floor(max_y - 0.5)));
        const double inv_area = 1.0 / area;
        for (int i = i0; i <= i1; ++i)
            for (int j = j0; j <= j1; ++j) {
                const Point q{j + 0.5, i + 0.5};
                const double wa = edge_function(b, c, q), wb = edge_function(c, a, q),
                             wc = edge_function(a, b, q);
                if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
                if ((wa == 0.0 && !own_bc) || (wb == 0.0 && !own_ca) || (wc == 0.0 && !own_ab)) continue;
                const std::size_t index = std::size_t(i) * std::size_t(size) + std::size_t(j);
                raster.triangle[index] = int(f);
                Vec3f w;
                w[order[0]] = float(wa * inv_area);
                w[order[1]] = float(wb * inv_area);
                w[order[2]] = float(wc * inv_area);
                raster.barycentric[index] = w;
            }
    }
    return raster;
}

void add_partial_texels(const TriangleMesh& mesh, UvRaster& raster) {
    TDF_CHECK(mesh.has_uvs());
    const int size = raster.size;
    const double s = double(size);
    for (std::size_t f = 0; f < mesh.uv_triangles.size(); ++f) {
        double xs[3], ys[3];
        for (int k = 0; k < 3; ++k) {
            const Vec2f uv = mesh.uvs[std::size_t(mesh.uv_triangles[f][k])];
            xs[k] = double(uv.x) * s;
            ys[k] = (1.0 - double(uv.y)) * s;
        }
        const double area2 = (xs[1] - xs[0]) * (ys[2] - ys[0]) - (ys[1] - ys[0]) * (xs[2] - xs[0]);
        if (!(area2 != 0.0) || !std::isfinite(area2)) continue;
        const int j0 = std::max(0, int(std::floor(std::min({xs[0], xs[1], xs[2]}))));
        const int j1 = std::min(size - 1, int(std::floor(std::max({xs[0], xs[1], xs[2]}))));
        const int i0 = std::max(0, int(std::floor(std::min({ys[0], ys[1], ys[2]}))));
        const int i1 = std::min(size - 1, int(std::floor(std::max({ys[0], ys[1], ys[2]}))));
        for (int i = i0; i <= i1; ++i)
            for (int j = j0; j <= j1; ++j) {
                const std::size_t t = std::size_t(i) * std::size_t(size) + std::size_t(j);
                if (raster.triangle[t] >= 0 || !triangle_touches_box(xs, ys, j, i, j + 1, i + 1)) continue;
                // The centre lies outside the triangle: its nearest point is on an edge.
                const double px = j + 0.5, py = i + 0.5;
                double best = 1e300;
                Vec3f weights;
                for (int k = 0; k < 3; ++k) {
                    const int k1 = (k + 1) % 3;
                    const double ex = xs[k1] - xs[k], ey = ys[k1] - ys[k];
                    const double length2 = ex * ex + ey * ey;
                    const double u =
                        length2 > 0 ? std::clamp(((px - xs[k]) * ex + (py - ys[k]) * ey) / length2, 0.0, 1.0)
                                    : 0.0;
                    const double dx = xs[k] + u * ex - px, dy = ys[k] + u * ey - py;
                    if (dx * dx + dy * dy < best) {
                        best = dx * dx + dy * dy;
                        weights = Vec3f{0, 0, 0};
                        weights[k] = float(1.0 - u);
                        weights[k1] = float(u);
                    }
                }
                raster.triangle[t] = int(f);
                raster.barycentric[t] = weights;
            }
    }
}

Image interpolate_vertex_attribute(const TriangleMesh& mesh, const UvRaster& raster,
                                   const std::vector<Vec3f>& attribute, Vec3f background) {
    TDF_CHECK_EQ(attribute.size(), mesh.positions.size());
    Image image(raster.size, raster.size, 3);
    parallel_for(raster.texel_count(), 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) {
            Vec3f value = background;
            const int f = raster.triangle[t];
            if (f >= 0) {
                const Vec3i& tri = mesh.triangles[std::size_t(f)];
                const Vec3f w = raster.barycentric[t];
                value = attribute[std::size_t(tri.x)] * w.x + attribute[std::size_t(tri.y)] * w.y +
                        attribute[std::size_t(tri.z)] * w.z;
            }
            float* out = image.data() + t * 3;
            out[0] = value.x;
            out[1] = value.y;
            out[2] = value.z;
        }
    });
    return image;
}

void sample_bilinear(const Image& image, Vec2f uv, float* out) {
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) uv = Vec2f{0.0f, 0.0f};
    sample_bilinear_uv(image, uv.x, uv.y, Addressing::Clamp, out);
}

}  // namespace tdf
