#include <tdf/tactile/contact_mask.h>

#include <tdf/core/error.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace tdf {

namespace {

struct Point {
    long long x, y;
};

long long cross(const Point& o, const Point& a, const Point& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Andrew's monotone chain; returns the hull counter-clockwise (in x right, y down: clockwise on
// screen) without repeated end point. Collinear points are dropped.
std::vector<Point> convex_hull(std::vector<Point> points) {
    std::sort(points.begin(), points.end(), [](const Point& a, const Point& b) {
        return a.x < b.x || (a.x == b.x && a.y < b.y);
    });
    if (points.size() < 3) return points;
    std::vector<Point> hull(2 * points.size());
    std::size_t k = 0;
    for (const Point& p : points) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0) --k;
        hull[k++] = p;
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1);
    return hull;
}

bool inside_convex(const std::vector<Point>& hull, const Point& p) {
    if (hull.size() < 3) {  // a point or a segment: inside when on it
        if (hull.size() == 1) return p.x == hull[0].x && p.y == hull[0].y;
        const Point &a = hull[0], &b = hull[1];
        return cross(a, b, p) == 0 && std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) &&
               std::min(a.y, b.y) <= p.y && p.y <= std::max(a.y, b.y);
    }
    for (std::size_t i = 0; i < hull.size(); ++i)
        if (cross(hull[i], hull[(i + 1) % hull.size()], p) < 0) return false;  // boundary counts
    return true;
}

}  // namespace

ContactRegion find_contact_region(const Image& height, float depth_threshold, const std::string& what) {
    TDF_CHECK_EQ(height.channels(), 1);
    const int w = height.width(), h = height.height();
    std::vector<std::uint8_t> above(std::size_t(w) * std::size_t(h));
    bool any = false;
    for (std::size_t i = 0; i < above.size(); ++i)
        any |= (above[i] = height.data()[i] > depth_threshold) != 0;
    if (!any)
        throw_error(
            "{}: empty contact mask: no pixel is higher than the depth threshold {} mm (try "
            "--depth-threshold, --invert or --contact off)",
            what,
            depth_threshold);

    // Dilate once with a 5x5 square (pixels outside the image do not count).
    std::vector<std::uint8_t> dilated(above.size(), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool hit = false;
            for (int dy = -2; dy <= 2 && !hit; ++dy)
                for (int dx = -2; dx <= 2 && !hit; ++dx) {
                    const int sx = x + dx, sy = y + dy;
                    hit = sx >= 0 && sx < w && sy >= 0 && sy < h &&
                          above[std::size_t(sy) * std::size_t(w) + std::size_t(sx)];
                }
            dilated[std::size_t(y) * std::size_t(w) + std::size_t(x)] = hit;
        }

    // Largest 8-connected component; ties go to the first found in raster order.
    std::vector<int> label(above.size(), -1);
    std::vector<std::size_t> stack, best_pixels, pixels;
    for (std::size_t seed = 0; seed < dilated.size(); ++seed) {
        if (!dilated[seed] || label[seed] >= 0) continue;
        pixels.clear();
        stack.assign(1, seed);
        label[seed] = int(seed);
        while (!stack.empty()) {
            const std::size_t p = stack.back();
            stack.pop_back();
            pixels.push_back(p);
            const int px = int(p % std::size_t(w)), py = int(p / std::size_t(w));
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = px + dx, ny = py + dy;
                    if (nx < 0 || nx >= w || ny < 0 || ny >= h) continue;
                    const std::size_t q = std::size_t(ny) * std::size_t(w) + std::size_t(nx);
                    if (dilated[q] && label[q] < 0) {
                        label[q] = int(seed);
                        stack.push_back(q);
                    }
                }
        }
        if (pixels.size() > best_pixels.size()) best_pixels.swap(pixels);
    }

    // Convex hull of the component from its per-row extremes, filled.
    std::vector<int> row_min(std::size_t(h), w), row_max(std::size_t(h), -1);
    for (std::size_t p : best_pixels) {
        const int px = int(p % std::size_t(w)), py = int(p / std::size_t(w));
        row_min[std::size_t(py)] = std::min(row_min[std::size_t(py)], px);
        row_max[std::size_t(py)] = std::max(row_max[std::size_t(py)], px);
    }
    std::vector<Point> extremes;
    for (int y = 0; y < h; ++y)
        if (row_max[std::size_t(y)] >= 0) {
            extremes.push_back({row_min[std::size_t(y)], y});
            extremes.push_back({row_max[std::size_t(y)], y});
        }
    const std::vector<Point> hull = convex_hull(extremes);
    ContactRegion region;
    region.mask = Image(w, h, 1);
    int x0 = w, y0 = h, x1 = -1, y1 = -1;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (inside_convex(hull, {x, y})) {
                region.mask.at(x, y, 0) = 1.0f;
                x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
            }
    TDF_CHECK(x1 >= x0 && y1 >= y0);

    // Matches reference: square by trimming the longer side, then a centre crop that keeps an
    // even side (spec 6.2 steps 4-5).
    int bw = x1 - x0 + 1, bh = y1 - y0 + 1;
    if (bw > bh) {
        x0 += (bw - bh) / 2;
        bw = bh;
    } else {
        y0 += (bh - bw) / 2;
        bh = bw;
    }
    region.x = x0;
    region.y = y0;
    region.side = 2 * (bw / 2);
    if (region.side < 2) throw_error("{}: the contact region is only {} pixel(s) wide", what, bw);
    return region;
}

}  // namespace tdf
