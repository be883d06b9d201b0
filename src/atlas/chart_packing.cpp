// Shape-based chart packing (see chart_packing.h): conservative chart masks placed in a texel
// bitmap, with a bisection on the scale.
#include <tdf/atlas/chart_packing.h>
#include <tdf/atlas/uv_metrics.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numeric>

namespace tdf {

namespace {

struct P2 {
    double x, y;
};

P2 rotated(P2 p, double c, double s) { return {c * p.x - s * p.y, s * p.x + c * p.y}; }

struct Box {
    double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
    void add(P2 p) {
        lo_x = std::min(lo_x, p.x);
        lo_y = std::min(lo_y, p.y);
        hi_x = std::max(hi_x, p.x);
        hi_y = std::max(hi_y, p.y);
    }
    double area() const { return (hi_x - lo_x) * (hi_y - lo_y); }
};

// A chart turned to its minimal-area bounding rectangle, with its lower-left corner at 0.
struct PreparedChart {
    std::vector<P2> points;
    std::vector<Vec3i> triangles;
    double width = 0, height = 0, area = 0;
};

PreparedChart prepare(const PackChart& chart) {
    PreparedChart out;
    out.triangles = chart.triangles;
    std::vector<P2> points(chart.uvs.size());
    for (std::size_t i = 0; i < points.size(); ++i) points[i] = {chart.uvs[i].x, chart.uvs[i].y};
    // Rotating calipers, simplified: the best rectangle has a side on a hull edge.
    std::vector<P2> hull;
    for (const Vec2f p : convex_hull(chart.uvs)) hull.push_back({p.x, p.y});
    double best_angle = 0, best_area = 1e300;
    for (std::size_t i = 0; i < hull.size() && hull.size() >= 3; ++i) {
        const P2 a = hull[i], b = hull[(i + 1) % hull.size()];
        const double angle = std::atan2(b.y - a.y, b.x - a.x);
        const double c = std::cos(-angle), s = std::sin(-angle);
        Box box;
        for (const P2 p : hull) box.add(rotated(p, c, s));
        if (box.area() < best_area * (1 - 1e-9)) {
            best_area = box.area();
            best_angle = angle;
        }
    }
    const double cos_a = std::cos(-best_angle), sin_a = std::sin(-best_angle);
    Box box;
    for (P2& p : points) {
        p = rotated(p, cos_a, sin_a);
        box.add(p);
    }
    for (P2& p : points) p = {p.x - box.lo_x, p.y - box.lo_y};
    out.points = std::move(points);
    out.width = std::max(box.hi_x - box.lo_x, 0.0);
    out.height = std::max(box.hi_y - box.lo_y, 0.0);
    for (const Vec3i& t : out.triangles) {
        const Vec2f a = chart.uvs[std::size_t(t.x)], b = chart.uvs[std::size_t(t.y)],
                    c = chart.uvs[std::size_t(t.z)];
        out.area += 0.5 * std::abs(signed_uv_area2(a, b, c));
    }
    return out;
}

// A chart's footprint in texels: cell (x, y) covers [x, x+1] x [y, y+1]; y grows upward (v).
struct Mask {
    int w = 0, h = 0;
    std::vector<std::uint8_t> cells;  // row-major, y * w + x
};

// Rasterizes the chart at `scale` texels per unit, offset by `margin` texels, then dilates by
// `margin` (square), so that two masks that do not overlap keep 2 * margin texels apart.
Mask rasterize_chart(const PreparedChart& chart, double scale, int margin) {
    Mask mask;
    mask.w = std::max(1, int(std::ceil(chart.width * scale))) + 2 * margin;
    mask.h = std::max(1, int(std::ceil(chart.height * scale))) + 2 * margin;
    mask.cells.assign(std::size_t(mask.w) * std::size_t(mask.h), 0);
    const auto texel = [&](P2 p) { return P2{p.x * scale + margin, p.y * scale + margin}; };
    for (const Vec3i& tri : chart.triangles) {
        double xs[3], ys[3];
        for (int k = 0; k < 3; ++k) {
            const P2 p = texel(chart.points[std::size_t(tri[k])]);
            xs[k] = p.x;
            ys[k] = p.y;
        }
        const int x0 = std::clamp(int(std::floor(std::min({xs[0], xs[1], xs[2]}))), 0, mask.w - 1);
        const int x1 = std::clamp(int(std::floor(std::max({xs[0], xs[1], xs[2]}))), 0, mask.w - 1);
        const int y0 = std::clamp(int(std::floor(std::min({ys[0], ys[1], ys[2]}))), 0, mask.h - 1);
        const int y1 = std::clamp(int(std::floor(std::max({ys[0], ys[1], ys[2]}))), 0, mask.h - 1);
        // Every texel the triangle touches, boundaries included: the mask is conservative.
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x)
                if (!mask.cells[std::size_t(y * mask.w + x)] &&
                    triangle_touches_box(xs, ys, x, y, x + 1, y + 1))
                    mask.cells[std::size_t(y * mask.w + x)] = 1;
    }
    if (margin > 0) {  // separable square dilation
        std::vector<std::uint8_t> tmp(mask.cells.size(), 0);
        for (int y = 0; y < mask.h; ++y)
            for (int x = 0; x < mask.w; ++x)
                if (mask.cells[std::size_t(y * mask.w + x)])
                    for (int d = std::max(0, x - margin); d <= std::min(mask.w - 1, x + margin); ++d)
                        tmp[std::size_t(y * mask.w + d)] = 1;
        std::fill(mask.cells.begin(), mask.cells.end(), 0);
        for (int y = 0; y < mask.h; ++y)
            for (int x = 0; x < mask.w; ++x)
                if (tmp[std::size_t(y * mask.w + x)])
                    for (int d = std::max(0, y - margin); d <= std::min(mask.h - 1, y + margin); ++d)
                        mask.cells[std::size_t(d * mask.w + x)] = 1;
    }
    return mask;
}

// 90 degrees counter-clockwise: cell (x, y) -> (h - 1 - y, x); continuous (x, y) -> (h - y, x).
Mask rotate(const Mask& m) {
    Mask r;
    r.w = m.h;
    r.h = m.w;
    r.cells.assign(m.cells.size(), 0);
    for (int y = 0; y < m.h; ++y)
        for (int x = 0; x < m.w; ++x)
            r.cells[std::size_t(x * r.w + (m.h - 1 - y))] = m.cells[std::size_t(y * m.w + x)];
    return r;
}

// Applies `turns` quarter turns (as `rotate`) to a point of a w x h mask.
P2 rotate_point(P2 p, int turns, double w, double h) {
    for (int k = 0; k < turns; ++k) {
        p = {h - p.y, p.x};
        std::swap(w, h);
    }
    return p;
}

struct Placement {
    int x = 0, y = 0, turns = 0;
};

// Runs of set cells per mask row: what a placement test checks.
struct Span {
    int row, begin, length;
};

// Reverses the low `bits` bits of `v`: the order 0, h/2, h/4, 3h/4, ... over rows.
unsigned reverse_bits(unsigned v, int bits) {
    unsigned r = 0;
    for (int i = 0; i < bits; ++i, v >>= 1) r = (r << 1) | (v & 1u);
    return r;
}

// Spans in bit-reversed row order: a collision anywhere in the mask is found after testing a
// few widely spaced rows rather than after sweeping up to it, which makes failed tests cheap.
std::vector<Span> spans_of(const Mask& m) {
    std::vector<Span> spans;
    for (int y = 0; y < m.h; ++y)
        for (int x = 0; x < m.w;) {
            if (!m.cells[std::size_t(y * m.w + x)]) {
                ++x;
                continue;
            }
            const int begin = x;
            while (x < m.w && m.cells[std::size_t(y * m.w + x)]) ++x;
            spans.push_back({y, begin, x - begin});
        }
    int bits = 0;
    while ((1 << bits) < m.h) ++bits;
    std::stable_sort(spans.begin(), spans.end(), [bits](const Span& a, const Span& b) {
        return reverse_bits(unsigned(a.row), bits) < reverse_bits(unsigned(b.row), bits);
    });
    return spans;
}

// The atlas as free runs: run[y][x] = number of free cells from (x, y) to the right. A span of
// length L fits at column c of row y iff run[y][c] >= L; when it does not, no position up to
// c + run[y][c] can hold it either, which lets the scan skip ahead.
class FreeRuns {
public:
    explicit FreeRuns(int size)
        : m_size(size),
          m_run(std::size_t(size) * std::size_t(size)),
          m_used(m_run.size(), 0),
          m_longest(std::size_t(size)),
          m_first_row(std::size_t(size) + 1, 0) {
        for (int y = 0; y < size; ++y) update_row(y);
    }
    int run(int x, int y) const { return m_run[std::size_t(y) * std::size_t(m_size) + std::size_t(x)]; }
    /// The longest free run in row y: a quick test that rules out whole rows.
    int longest_run(int y) const { return m_longest[std::size_t(y)]; }
    /// The lowest row holding a free run of at least `length` cells (`size` when none). Runs only
    /// shrink as charts are placed, so this only moves up: the pointers advance lazily.
    int first_row_with_run(int length) {
        int& row = m_first_row[std::size_t(length)];
        while (row < m_size && m_longest[std::size_t(row)] < length) ++row;
        return row;
    }
    void occupy(const std::vector<Span>& spans, int x, int y, int h) {
        for (const Span& s : spans)
            std::fill_n(m_used.begin() + std::ptrdiff_t(std::size_t(y + s.row) * std::size_t(m_size) +
                                                        std::size_t(x + s.begin)),
                        s.length,
                        std::uint8_t(1));
        for (int r = y; r < y + h; ++r) update_row(r);
    }

private:
    void update_row(int y) {
        const std::size_t base = std::size_t(y) * std::size_t(m_size);
        int run = 0, longest = 0;
        for (int x = m_size - 1; x >= 0; --x) {
            run = m_used[base + std::size_t(x)] ? 0 : run + 1;
            m_run[base + std::size_t(x)] = run;
            longest = std::max(longest, run);
        }
        m_longest[std::size_t(y)] = longest;
    }
    int m_size;
    std::vector<int> m_run;
    std::vector<std::uint8_t> m_used;
    std::vector<int> m_longest;
    std::vector<int> m_first_row;  // per run length
};

// Lowest (then leftmost) position where the mask fits, scanning rows bottom-up with free-run
// skips; false when it fits nowhere. Rows at or above `stop_y` are not scanned.
bool lowest_fit(FreeRuns& atlas, const Mask& m, const std::vector<Span>& spans, int size, int stop_y,
                int& fit_x, int& fit_y) {
    // No position lies below the row at which every span first finds a long enough run.
    int start = 0;
    for (const Span& s : spans) start = std::max(start, atlas.first_row_with_run(s.length) - s.row);
    for (int y = start; y + m.h <= size && y < stop_y; ++y) {
        bool possible = true;
        for (const Span& s : spans)
            if (atlas.longest_run(y + s.row) < s.length) {
                possible = false;
                break;
            }
        if (!possible) continue;
        for (int x = 0; x + m.w <= size;) {
            int skip = 0;
            for (const Span& s : spans) {
                const int run = atlas.run(x + s.begin, y + s.row);
                if (run < s.length) {
                    skip = run + 1;
                    break;
                }
            }
            if (skip == 0) {
                fit_x = x;
                fit_y = y;
                return true;
            }
            x += skip;
        }
    }
    return false;
}

// A chart's masks at one scale, in its four quarter turns, with their spans.
struct TurnedMasks {
    Mask masks[4];
    std::vector<Span> spans[4];
};

std::vector<TurnedMasks> rasterize_all(const std::vector<PreparedChart>& charts, double scale, int margin) {
    std::vector<TurnedMasks> all(charts.size());
    parallel_for(charts.size(), 4, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            all[i].masks[0] = rasterize_chart(charts[i], scale, margin);
            for (int r = 1; r < 4; ++r) all[i].masks[r] = rotate(all[i].masks[r - 1]);
            for (int r = 0; r < 4; ++r) all[i].spans[r] = spans_of(all[i].masks[r]);
        }
    });
    return all;
}

// Places every chart (in `order`) at the lowest position over its four quarter turns, keeping
// the top of the placed chart lowest; false when one does not fit.
bool try_pack(const std::vector<TurnedMasks>& charts, const std::vector<std::size_t>& order, int size,
              std::vector<Placement>& placements) {
    FreeRuns atlas(size);
    placements.assign(charts.size(), Placement{});
    for (const std::size_t i : order) {
        const TurnedMasks& chart = charts[i];
        int best_top = size + 1;
        Placement best;
        for (int r = 0; r < 4; ++r) {
            const Mask& m = chart.masks[r];
            if (m.w > size || m.h > size) continue;
            int x = 0, y = 0;
            // Only positions whose top would beat the best so far are worth scanning.
            if (lowest_fit(atlas, m, chart.spans[r], size, best_top - m.h, x, y) && y + m.h < best_top) {
                best_top = y + m.h;
                best = {x, y, r};
            }
        }
        if (best_top > size) return false;
        atlas.occupy(chart.spans[best.turns], best.x, best.y, chart.masks[best.turns].h);
        placements[i] = best;
    }
    return true;
}

}  // namespace

// The densest mask coverage the greedy packer is expected to reach; used to skip hopeless scales.
constexpr double kMaxMaskFill = 0.92;

double pack_charts(std::vector<PackChart>& charts, int size, int gutter) {
    if (charts.empty()) return 1.0;
    std::vector<PreparedChart> prepared(charts.size());
    parallel_for(charts.size(), 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) prepared[i] = prepare(charts[i]);
    });
    // Three greedy orders, largest first by bounding-rectangle area, by longest side and by
    // area (stable sorts: ties keep chart order). A scale counts as fitting when any order fits.
    std::vector<std::vector<std::size_t>> orders(3, std::vector<std::size_t>(charts.size()));
    const std::function<double(const PreparedChart&)> keys[3] = {
        [](const PreparedChart& c) { return c.width * c.height; },
        [](const PreparedChart& c) { return std::max(c.width, c.height); },
        [](const PreparedChart& c) { return c.area; }};
    for (int k = 0; k < 3; ++k) {
        std::iota(orders[std::size_t(k)].begin(), orders[std::size_t(k)].end(), std::size_t(0));
        std::stable_sort(
            orders[std::size_t(k)].begin(), orders[std::size_t(k)].end(), [&](std::size_t a, std::size_t b) {
                return keys[k](prepared[a]) > keys[k](prepared[b]);
            });
    }
    double total_area = 0;
    for (const PreparedChart& c : prepared) total_area += c.area;
    const int margin = (gutter + 1) / 2;
    std::vector<Placement> placements, best_placements;
    // Masks never overlap, so their total area bounds what can fit: scales whose masks exceed
    // the square are rejected without packing, and the search jumps below them.
    const double texels = double(size) * double(size);
    const auto mask_area = [](const std::vector<TurnedMasks>& masks) {
        double area = 0;
        for (const TurnedMasks& m : masks)
            for (const Span& span : m.spans[0]) area += span.length;
        return area;
    };
    const auto pack = [&](const std::vector<TurnedMasks>& masks) {
        for (const auto& order : orders)
            if (try_pack(masks, order, size, placements)) {
                best_placements = placements;
                return true;
            }
        return false;
    };

    // Shrink from 85 % utilisation in ~10 % area steps until everything fits, then bisect.
    const double upper_bound = double(size) / std::sqrt(std::max(total_area, 1e-300));
    double fail = upper_bound, success = 0;
    for (double s = upper_bound * std::sqrt(0.85); s > upper_bound * 1e-3;) {
        const std::vector<TurnedMasks> masks = rasterize_all(prepared, s, margin);
        const double area = mask_area(masks);
        if (area <= kMaxMaskFill * texels && pack(masks)) {
            success = s;
            break;
        }
        fail = s;
        s *= area > kMaxMaskFill * texels ? 0.999 * std::sqrt(kMaxMaskFill * texels / area) : std::sqrt(0.9);
    }
    if (success == 0)
        throw_error(
            "atlas: {} charts do not fit into {}x{} texels with a {}-texel gutter; use a larger --size or a "
            "smaller --gutter",
            charts.size(),
            size,
            size,
            gutter);
    for (int iteration = 0; iteration < 7 && fail / success > 1.003; ++iteration) {
        const double s = std::sqrt(success * fail);
        std::vector<Placement> kept = best_placements;
        const std::vector<TurnedMasks> masks = rasterize_all(prepared, s, margin);
        if (mask_area(masks) <= texels && pack(masks)) {
            success = s;
        } else {
            fail = s;
            best_placements = std::move(kept);
        }
    }

    // Write the packed coordinates back: the same transform the masks went through.
    for (std::size_t i = 0; i < charts.size(); ++i) {
        const PreparedChart& c = prepared[i];
        const Placement& p = best_placements[i];
        const double w = std::max(1, int(std::ceil(c.width * success))) + 2 * margin;
        const double h = std::max(1, int(std::ceil(c.height * success))) + 2 * margin;
        for (std::size_t v = 0; v < c.points.size(); ++v) {
            const P2 local{c.points[v].x * success + margin, c.points[v].y * success + margin};
            const P2 turned = rotate_point(local, p.turns, w, h);
            charts[i].uvs[v] = Vec2f(float((turned.x + p.x) / size), float((turned.y + p.y) / size));
        }
    }
    return success;
}

}  // namespace tdf
