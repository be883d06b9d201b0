#include <tdf/atlas/surface_height.h>

#include <tdf/atlas/gutter.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace tdf {

namespace {

constexpr std::size_t kChunk = 4096;  // fixed chunks: sums do not depend on the thread count
constexpr int kAggregate = 8;         // texels per side of a coarse node
constexpr int kCycles = 3;            // coarse correction + fine smoothing rounds
constexpr int kFineIterations = 40;   // per round
constexpr int kCoarseIterations = 2000;
constexpr double kCoarseTolerance = 1e-6;

/// A weighted graph Laplacian, (A x)_i = sum_j w_ij (x_i - x_j), in compressed rows: the coarse
/// levels (blocks of texels, charts). The texel level is a TexelGraph.
struct Graph {
    std::vector<std::uint32_t> offset;  // n + 1
    std::vector<int> neighbour;
    std::vector<float> weight;
    std::vector<double> diagonal;

    std::size_t size() const { return diagonal.size(); }
    double diagonal_at(std::size_t i) const { return diagonal[i]; }
};

/// Builds a graph from undirected edges (i, j, weight) with i != j, merged when repeated.
Graph make_graph(std::size_t n, std::vector<std::pair<std::pair<int, int>, float>> edges) {
    for (auto& e : edges)
        if (e.first.first > e.first.second) std::swap(e.first.first, e.first.second);
    std::sort(edges.begin(), edges.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<std::pair<std::pair<int, int>, float>> merged;
    for (const auto& e : edges) {
        if (!merged.empty() && merged.back().first == e.first) merged.back().second += e.second;
        else merged.push_back(e);
    }
    Graph g;
    g.offset.assign(n + 1, 0);
    for (const auto& e : merged) ++g.offset[std::size_t(e.first.first) + 1], ++g.offset[std::size_t(e.first.second) + 1];
    std::partial_sum(g.offset.begin(), g.offset.end(), g.offset.begin());
    g.neighbour.resize(g.offset[n]);
    g.weight.resize(g.offset[n]);
    g.diagonal.assign(n, 0.0);
    std::vector<std::uint32_t> fill(g.offset.begin(), g.offset.end() - 1);
    for (const auto& e : merged) {
        const auto [i, j] = e.first;
        g.neighbour[fill[std::size_t(i)]] = j, g.weight[fill[std::size_t(i)]++] = e.second;
        g.neighbour[fill[std::size_t(j)]] = i, g.weight[fill[std::size_t(j)]++] = e.second;
        g.diagonal[std::size_t(i)] += e.second, g.diagonal[std::size_t(j)] += e.second;
    }
    return g;
}

void multiply(const Graph& g, const std::vector<double>& x, std::vector<double>& out) {
    parallel_for(g.size(), kChunk, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            double s = g.diagonal_at(i) * x[i];
            for (std::size_t k = g.offset[i]; k < g.offset[i + 1]; ++k)
                s -= double(g.weight[k]) * x[std::size_t(g.neighbour[k])];
            out[i] = s;
        }
    });
}

/// The sum of term(i) over [0, n), in fixed chunks: the same bits on any thread count.
template <class Term>
double chunked_sum(std::size_t n, Term&& term) {
    std::vector<double> partial(chunk_count(n, kChunk), 0.0);
    parallel_for(partial.size(), 1, [&](std::size_t c0, std::size_t c1) {
        for (std::size_t c = c0; c < c1; ++c) {
            double s = 0;
            for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) s += term(i);
            partial[c] = s;
        }
    });
    return std::accumulate(partial.begin(), partial.end(), 0.0);
}

double dot(const std::vector<double>& a, const std::vector<double>& b) {
    return chunked_sum(a.size(), [&](std::size_t i) { return a[i] * b[i]; });
}

/// Jacobi-preconditioned conjugate gradients on A x = b from x; stops after `iterations` or at
/// |r| <= tolerance |b|. Returns the iterations run.
template <class G>
int conjugate_gradients(const G& g, const std::vector<double>& b, std::vector<double>& x, int iterations,
                        double tolerance) {
    const std::size_t n = g.size();
    // The preconditioned residual z = r / diagonal is not stored: it is recomputed where it is
    // read (the same values, so the same sums), one vector of n doubles less.
    std::vector<double> r(n), p(n), q(n);
    multiply(g, x, q);
    for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - q[i];
    const double stop = tolerance * tolerance * dot(b, b);
    const auto z = [&](std::size_t i) {
        const double d = g.diagonal_at(i);
        return d > 0 ? r[i] / d : 0.0;
    };
    const auto r_dot_z = [&] { return chunked_sum(n, [&](std::size_t i) { return r[i] * z(i); }); };
    for (std::size_t i = 0; i < n; ++i) p[i] = z(i);
    double rz = r_dot_z();
    int k = 0;
    for (; k < iterations && dot(r, r) > stop && rz > 0; ++k) {
        multiply(g, p, q);
        const double pq = dot(p, q);
        if (!(pq > 0)) break;
        const double alpha = rz / pq;
        for (std::size_t i = 0; i < n; ++i) x[i] += alpha * p[i], r[i] -= alpha * q[i];
        const double rz_next = r_dot_z();
        const double beta = rz_next / rz;
        rz = rz_next;
        for (std::size_t i = 0; i < n; ++i) p[i] = z(i) + beta * p[i];
    }
    return k;
}

/// Covered texel i's neighbour at (x + dx, y + dy) when it is covered and on i's chart, else -1.
int chart_neighbour(const SurfaceTexels& s, std::size_t i, int dx, int dy) {
    const int x = int(s.texels[i] % std::uint32_t(s.size)) + dx, y = int(s.texels[i] / std::uint32_t(s.size)) + dy;
    if (x < 0 || y < 0 || x >= s.size || y >= s.size) return -1;
    const int j = s.node[std::size_t(y) * std::size_t(s.size) + std::size_t(x)];
    return j >= 0 && s.chart[std::size_t(j)] == s.chart[i] ? j : -1;
}

/// The change of `height` (the map, indexed by texel) per texel step along (dx, dy) at covered
/// texel i: central where both neighbours are on its chart, else one-sided, else 0.
double chart_difference(const SurfaceTexels& s, const float* height, std::size_t i, int dx, int dy) {
    const int lo = chart_neighbour(s, i, -dx, -dy), hi = chart_neighbour(s, i, dx, dy);
    const auto at = [&](int j) { return double(height[s.texels[std::size_t(j)]]); };
    if (lo >= 0 && hi >= 0) return 0.5 * (at(hi) - at(lo));
    if (hi >= 0) return at(hi) - at(int(i));
    if (lo >= 0) return at(int(i)) - at(lo);
    return 0.0;
}

/// The texel graph, every edge of weight 1, held implicitly: a covered texel's neighbours are
/// the 4 texels around it on its chart (one bit each) and its partners across seams. They are
/// visited in the order a compressed-row copy of the edge list held them (up, left, right,
/// down, then the seam partners in link order), so every sum has the same bits as with that
/// copy, without its 20 bytes a texel (320 MB at 4096^2 maps).
class TexelGraph {
public:
    using SeamCursor = std::vector<std::pair<int, int>>::const_iterator;

    explicit TexelGraph(const SurfaceTexels& s)
        : m_s(&s), m_sides(s.covered_count(), 0), m_degree(s.covered_count(), 0) {
        m_seams.reserve(2 * s.seam_links.size());
        for (const auto& [a, b] : s.seam_links) m_seams.push_back({a, b}), m_seams.push_back({b, a});
        std::stable_sort(m_seams.begin(), m_seams.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
        parallel_for(s.covered_count(), kChunk, [&](std::size_t begin, std::size_t end) {
            SeamCursor seam = seams_from(begin);
            for (std::size_t i = begin; i < end; ++i) {
                const int sides = (chart_neighbour(s, i, 0, -1) >= 0 ? kUp : 0) |
                                  (chart_neighbour(s, i, -1, 0) >= 0 ? kLeft : 0) |
                                  (chart_neighbour(s, i, 1, 0) >= 0 ? kRight : 0) |
                                  (chart_neighbour(s, i, 0, 1) >= 0 ? kDown : 0);
                int degree = __builtin_popcount(unsigned(sides));
                for (; seam != m_seams.end() && std::size_t(seam->first) == i; ++seam) ++degree;
                TDF_CHECK(degree <= 255);
                m_sides[i] = std::uint8_t(sides), m_degree[i] = std::uint8_t(degree);
            }
        });
    }

    std::size_t size() const { return m_sides.size(); }
    double diagonal_at(std::size_t i) const { return double(m_degree[i]); }

    /// The first seam partner of texel `begin` or after: where a pass from `begin` starts.
    SeamCursor seams_from(std::size_t begin) const {
        return std::lower_bound(m_seams.begin(), m_seams.end(), begin,
                                [](const std::pair<int, int>& e, std::size_t i) { return std::size_t(e.first) < i; });
    }

    /// visit(j) for each neighbour j of texel i, in the order above; `seam` (from seams_from, for
    /// ascending i) moves past i's partners.
    template <class Visit>
    void visit_neighbours(std::size_t i, SeamCursor& seam, Visit&& visit) const {
        const std::size_t t = m_s->texels[i], row = std::size_t(m_s->size);
        const int sides = m_sides[i];
        if (sides & kUp) visit(std::size_t(m_s->node[t - row]));
        if (sides & kLeft) visit(std::size_t(m_s->node[t - 1]));
        if (sides & kRight) visit(std::size_t(m_s->node[t + 1]));
        if (sides & kDown) visit(std::size_t(m_s->node[t + row]));
        for (; seam != m_seams.end() && std::size_t(seam->first) == i; ++seam) visit(std::size_t(seam->second));
    }

private:
    static constexpr int kUp = 1, kLeft = 2, kRight = 4, kDown = 8;
    const SurfaceTexels* m_s;
    std::vector<std::uint8_t> m_sides, m_degree;
    std::vector<std::pair<int, int>> m_seams;  // (texel, partner), both ways, by texel, in link order
};

void multiply(const TexelGraph& g, const std::vector<double>& x, std::vector<double>& out) {
    parallel_for(g.size(), kChunk, [&](std::size_t begin, std::size_t end) {
        TexelGraph::SeamCursor seam = g.seams_from(begin);
        for (std::size_t i = begin; i < end; ++i) {
            double s = g.diagonal_at(i) * x[i];
            g.visit_neighbours(i, seam, [&](std::size_t j) { s -= x[j]; });
            out[i] = s;
        }
    });
}

/// The normal equations of the texel graph: A (unit weights) and b_i = -sum_j g_ij, g_ij the
/// wanted h_j - h_i in mm.
struct Problem {
    TexelGraph fine;
    std::vector<double> rhs;
};

Problem texel_problem(const Image& texture_mm, float texture_mm_per_texel, const SurfaceTexels& s, float mm_per_unit,
                      HeightMetric metric) {
    const std::size_t n = s.covered_count();
    const auto height = [&](int j) { return double(texture_mm.data()[s.texels[std::size_t(j)]]); };
    // The texture-space heights' slope along T at each texel (the surface metric's only).
    std::vector<double> slope_t(metric == HeightMetric::Surface ? n : 0, 0.0);
    parallel_for(slope_t.size(), kChunk, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            slope_t[i] = chart_difference(s, texture_mm.data(), i, 1, 0) / double(texture_mm_per_texel);
    });
    Problem problem{TexelGraph(s), std::vector<double>(n, 0.0)};
    // The edges are the graph's (TexelGraph: the same 4-neighbours on the chart, and the seams).
    const auto link = [&](int i, int j, double wanted) {
        problem.rhs[std::size_t(i)] -= wanted;
        problem.rhs[std::size_t(j)] += wanted;
    };
    // Each edge keeps the texture-space heights' own difference (so their fine structure, which
    // matches the normal map's central differences, stays), turned into the slopes it stands
    // for and taken over the surface step between the two texels.
    const double m = mm_per_unit, inv = 1.0 / double(texture_mm_per_texel);
    for (std::size_t i = 0; i < n; ++i) {
        const TexelStep& a = s.step[i];
        if (metric == HeightMetric::Map) {  // the texture-space differences as they are
            if (const int j = chart_neighbour(s, i, 1, 0); j >= 0) link(int(i), j, height(j) - height(int(i)));
            if (const int j = chart_neighbour(s, i, 0, 1); j >= 0) link(int(i), j, height(j) - height(int(i)));
            continue;
        }
        if (const int j = chart_neighbour(s, i, 1, 0); j >= 0) {
            const double along_t = (height(j) - height(int(i))) * inv;
            link(int(i), j, m * 0.5 * (double(a.along_x_t) + s.step[std::size_t(j)].along_x_t) * along_t);
        }
        if (const int j = chart_neighbour(s, i, 0, 1); j >= 0) {
            const TexelStep& b = s.step[std::size_t(j)];
            const double along_b = -(height(j) - height(int(i))) * inv;  // a row down is -v
            const double along_t = 0.5 * (slope_t[i] + slope_t[std::size_t(j)]);
            link(int(i), j, m * (0.5 * (double(a.along_y_t) + b.along_y_t) * along_t +
                                 0.5 * (double(a.along_y_b) + b.along_y_b) * along_b));
        }
    }
    for (const auto& [i, j] : s.seam_links) link(i, j, 0.0);  // level across the seam
    return problem;
}

/// Galerkin coarse graph over kAggregate^2-texel blocks of one chart: weights count the fine
/// edges between two blocks.
struct Coarse {
    std::vector<int> of;  // per fine node
    Graph graph;
};

Coarse coarse_graph(const SurfaceTexels& s, const TexelGraph& fine) {
    Coarse c;
    const std::size_t n = s.covered_count();
    const std::uint64_t blocks = std::uint64_t(s.size / kAggregate + 1);
    const auto key = [&](std::size_t i) {
        const std::uint64_t x = s.texels[i] % std::uint32_t(s.size) / kAggregate, y = s.texels[i] / std::uint32_t(s.size) / kAggregate;
        return (std::uint64_t(s.chart[i]) * blocks + y) * blocks + x;
    };
    // Coarse nodes numbered in key order: the distinct keys (one a block, ~n / 64) sorted, then
    // each texel's found by bisection; no sorted copy of all n keys (16 bytes a texel).
    std::vector<std::uint64_t> keys;
    for (std::size_t i = 0; i < n; ++i)
        if (const std::uint64_t k = key(i); keys.empty() || keys.back() != k) keys.push_back(k);
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    c.of.assign(n, -1);
    parallel_for(n, kChunk, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            c.of[i] = int(std::lower_bound(keys.begin(), keys.end(), key(i)) - keys.begin());
    });
    // Each fine edge once (from its lower end); the weights count them, so the order does not matter.
    std::vector<std::pair<std::pair<int, int>, float>> weighted;
    TexelGraph::SeamCursor seam = fine.seams_from(0);
    for (std::size_t i = 0; i < n; ++i)
        fine.visit_neighbours(i, seam, [&](std::size_t j) {
            const int a = c.of[i], b = c.of[j];
            if (i < j && a != b) weighted.push_back({{a, b}, 1.0f});
        });
    c.graph = make_graph(keys.size(), std::move(weighted));
    return c;
}

/// h += the coarse solution of A_c e = R (b - A h), prolonged piecewise constant.
void coarse_correction(const Problem& p, const Coarse& c, std::vector<double>& h) {
    std::vector<double> r(h.size());
    multiply(p.fine, h, r);
    std::vector<double> rc(c.graph.size(), 0.0), e(c.graph.size(), 0.0);
    for (std::size_t i = 0; i < h.size(); ++i) rc[std::size_t(c.of[i])] += p.rhs[i] - r[i];
    conjugate_gradients(c.graph, rc, e, kCoarseIterations, kCoarseTolerance);
    for (std::size_t i = 0; i < h.size(); ++i) h[i] += e[std::size_t(c.of[i])];
}

/// The map of per-covered-texel heights `h`, less their mean (zero mean over the covered
/// texels, as the texture-space integration), with the gutter filled.
Image covered_heights_map(const std::vector<double>& h, const SurfaceTexels& surface) {
    const double mean = h.empty() ? 0.0 : std::accumulate(h.begin(), h.end(), 0.0) / double(h.size());
    Image out(surface.size, surface.size, 1);
    for (std::size_t i = 0; i < h.size(); ++i) out.data()[surface.texels[i]] = float(h[i] - mean);
    dilate_gutter(out, surface.node, 0);
    return out;
}

}  // namespace

Image heights_on_surface(const Image& texture_mm, float texture_mm_per_texel, const SurfaceTexels& surface,
                         float mm_per_unit, HeightMetric metric, SurfaceHeightStats* stats) {
    TDF_CHECK(texture_mm.channels() == 1 && texture_mm.width() == surface.size && texture_mm.height() == surface.size);
    TDF_CHECK(mm_per_unit > 0 && texture_mm_per_texel > 0);
    const Problem problem = texel_problem(texture_mm, texture_mm_per_texel, surface, mm_per_unit, metric);
    const Coarse coarse = coarse_graph(surface, problem.fine);
    std::vector<double> h(surface.covered_count());
    for (std::size_t i = 0; i < h.size(); ++i) h[i] = texture_mm.data()[surface.texels[i]];
    int iterations = 0;
    for (int cycle = 0; cycle < kCycles; ++cycle) {
        coarse_correction(problem, coarse, h);
        iterations += conjugate_gradients(problem.fine, problem.rhs, h, kFineIterations, 0.0);
    }
    Image out = covered_heights_map(h, surface);
    if (stats) {
        std::vector<double> r(h.size());
        multiply(problem.fine, h, r);
        for (std::size_t i = 0; i < h.size(); ++i) r[i] = problem.rhs[i] - r[i];
        const double b = dot(problem.rhs, problem.rhs);
        stats->iterations = iterations;
        stats->relative_residual = b > 0 ? std::sqrt(dot(r, r) / b) : 0.0;
    }
    return out;
}

Image level_chart_offsets(const Image& texture_mm, const SurfaceTexels& surface) {
    TDF_CHECK(texture_mm.channels() == 1 && texture_mm.width() == surface.size && texture_mm.height() == surface.size);
    const int charts = surface.chart.empty() ? 0 : *std::max_element(surface.chart.begin(), surface.chart.end()) + 1;
    // One unknown per chart: c_B - c_A should be h_a - h_b for every link (a in A, b in B).
    std::vector<double> rhs(std::size_t(charts), 0.0), offset(std::size_t(charts), 0.0);
    std::vector<std::pair<std::pair<int, int>, float>> weighted;
    for (const auto& [a, b] : surface.seam_links) {
        const int ca = surface.chart[std::size_t(a)], cb = surface.chart[std::size_t(b)];
        if (ca == cb) continue;
        const double wanted = double(texture_mm.data()[surface.texels[std::size_t(a)]]) -
                              texture_mm.data()[surface.texels[std::size_t(b)]];
        rhs[std::size_t(ca)] -= wanted, rhs[std::size_t(cb)] += wanted;
        weighted.push_back({{ca, cb}, 1.0f});
    }
    const Graph graph = make_graph(std::size_t(charts), std::move(weighted));
    conjugate_gradients(graph, rhs, offset, kCoarseIterations, kCoarseTolerance);
    std::vector<double> h(surface.covered_count());
    for (std::size_t i = 0; i < h.size(); ++i)
        h[i] = texture_mm.data()[surface.texels[i]] + offset[std::size_t(surface.chart[i])];
    return covered_heights_map(h, surface);
}

double surface_height_consistency(const Image& height_mm, const Image& normals, const SurfaceTexels& s,
                                  float mm_per_unit) {
    TDF_CHECK(height_mm.width() == s.size && height_mm.height() == s.size && normals.channels() >= 3);
    TDF_CHECK(mm_per_unit > 0);
    const std::size_t n = s.covered_count();
    std::vector<double> cosine(n, 0.0);
    parallel_for(n, kChunk, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const auto difference = [&](int dx, int dy) { return chart_difference(s, height_mm.data(), i, dx, dy); };
            const TexelStep& d = s.step[i];
            // Invert gx = m st ax, gy = m (st ayt + sb ayb) for the slopes along T and B.
            const double st = difference(1, 0) / (double(mm_per_unit) * d.along_x_t);
            const double sb = (difference(0, 1) / double(mm_per_unit) - st * d.along_y_t) / d.along_y_b;
            const double length = std::sqrt(st * st + sb * sb + 1.0);
            const float* m = normals.data() + std::size_t(s.texels[i]) * std::size_t(normals.channels());
            const double m_length = std::sqrt(double(m[0]) * m[0] + double(m[1]) * m[1] + double(m[2]) * m[2]);
            if (m_length > 0) cosine[i] = (-st * m[0] - sb * m[1] + m[2]) / (length * m_length);
        }
    });
    return n > 0 ? std::accumulate(cosine.begin(), cosine.end(), 0.0) / double(n) : 0.0;
}

}  // namespace tdf
