// Chart segmentation, flattening and assembly of the UV atlas (pipeline in uv_atlas.h).
#include <tdf/atlas/chart_packing.h>
#include <tdf/atlas/chart_parameterization.h>
#include <tdf/atlas/uv_atlas.h>
#include <tdf/atlas/uv_metrics.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/core/progress.h>
#include <tdf/core/union_find.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <queue>
#include <unordered_map>

namespace tdf {

namespace {

struct D3 {
    double x = 0, y = 0, z = 0;
};
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
D3 to_d3(Vec3f v) { return {v.x, v.y, v.z}; }
D3 normalized(D3 a) {
    const double n = std::sqrt(dot(a, a));
    return n > 0 ? a * (1.0 / n) : D3{};
}

// What the chart builder knows about the surface: welded vertices, per-face geometry and the
// face across each edge (corner k -> k+1), -1 for borders, seams of non-manifold or
// inconsistently oriented edges, and edges of degenerate faces.
struct Surface {
    const TriangleMesh* mesh = nullptr;
    std::vector<int> welded;                         // per position
    std::vector<D3> normal, centroid;                // per face
    std::vector<double> area;                        // per face
    std::vector<std::uint8_t> degenerate;            // per face
    std::vector<std::array<int, 3>> neighbour;       // per face edge
    std::vector<std::array<int, 3>> neighbour_edge;  // the same edge's slot in the neighbour
    double diagonal = 1;

    int vertex(int face, int corner) const {
        return welded[std::size_t(mesh->triangles[std::size_t(face)][corner])];
    }
};

Surface analyse_surface(const TriangleMesh& mesh) {
    Surface s;
    s.mesh = &mesh;
    const Bounds3 bounds = compute_bounds(mesh);
    s.diagonal = std::max(double(length(bounds.extent())), 1e-30);

    // Weld positions on a grid of 1e-6 of the diagonal (ids in first-seen order: deterministic).
    const double cell = s.diagonal * 1e-6;
    struct KeyHash {
        std::size_t operator()(const std::array<std::int64_t, 3>& k) const {
            return std::size_t(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
        }
    };
    std::unordered_map<std::array<std::int64_t, 3>, int, KeyHash> ids;
    s.welded.resize(mesh.positions.size());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        const Vec3f p = mesh.positions[i] - bounds.lower;
        const std::array<std::int64_t, 3> key = {std::int64_t(std::llround(p.x / cell)),
                                                 std::int64_t(std::llround(p.y / cell)),
                                                 std::int64_t(std::llround(p.z / cell))};
        s.welded[i] = ids.emplace(key, int(ids.size())).first->second;
    }

    const std::size_t faces = mesh.triangles.size();
    s.normal.resize(faces);
    s.centroid.resize(faces);
    s.area.resize(faces);
    s.degenerate.resize(faces);
    const double min_area = 1e-14 * s.diagonal * s.diagonal;
    for (std::size_t f = 0; f < faces; ++f) {
        const Vec3i& t = mesh.triangles[f];
        const D3 a = to_d3(mesh.positions[std::size_t(t.x)]), b = to_d3(mesh.positions[std::size_t(t.y)]),
                 c = to_d3(mesh.positions[std::size_t(t.z)]);
        const D3 n = cross(b - a, c - a);
        s.area[f] = 0.5 * std::sqrt(dot(n, n));
        s.normal[f] = normalized(n);
        s.centroid[f] = (a + b + c) * (1.0 / 3.0);
        s.degenerate[f] = !(s.area[f] > min_area);
    }

    // Edges: sort (undirected key, face, slot) and link exactly-two-face, opposite-direction pairs.
    struct EdgeEntry {
        std::uint64_t key;
        int face, slot;
        bool forward;
    };
    std::vector<EdgeEntry> edges;
    edges.reserve(faces * 3);
    for (std::size_t f = 0; f < faces; ++f) {
        if (s.degenerate[f]) continue;
        for (int k = 0; k < 3; ++k) {
            const int a = s.vertex(int(f), k), b = s.vertex(int(f), (k + 1) % 3);
            if (a == b) continue;  // corners welded together: no edge to cross
            const auto lo = std::uint64_t(std::min(a, b)), hi = std::uint64_t(std::max(a, b));
            edges.push_back({(lo << 32) | hi, int(f), k, a < b});
        }
    }
    std::sort(edges.begin(), edges.end(), [](const EdgeEntry& x, const EdgeEntry& y) {
        return x.key < y.key ||
               (x.key == y.key && (x.face < y.face || (x.face == y.face && x.slot < y.slot)));
    });
    s.neighbour.assign(faces, {-1, -1, -1});
    s.neighbour_edge.assign(faces, {-1, -1, -1});
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j].key == edges[i].key) ++j;
        if (j - i == 2 && edges[i].forward != edges[i + 1].forward && edges[i].face != edges[i + 1].face) {
            const EdgeEntry &a = edges[i], &b = edges[i + 1];
            s.neighbour[std::size_t(a.face)][a.slot] = b.face;
            s.neighbour_edge[std::size_t(a.face)][a.slot] = b.slot;
            s.neighbour[std::size_t(b.face)][b.slot] = a.face;
            s.neighbour_edge[std::size_t(b.face)][b.slot] = a.slot;
        }
        i = j;  // more than two faces, or inconsistent winding: the edge stays a seam
    }
    return s;
}

// Greedy growth leaves saw-toothed borders (faces poking into the next chart), which cost
// packing space and gutter. A face with two of its three neighbours in another chart moves there
// when its normal fits that chart's cone. A few sequential passes in face order (deterministic).
void smooth_chart_borders(const Surface& s, double cos_sharp, double cos_cone, std::vector<int>& chart_of,
                          std::size_t chart_count) {
    const std::size_t faces = chart_of.size();
    for (int pass = 0; pass < 4; ++pass) {
        std::vector<D3> normal_sum(chart_count);
        for (std::size_t f = 0; f < faces; ++f)
            if (chart_of[f] >= 0)
                normal_sum[std::size_t(chart_of[f])] =
                    normal_sum[std::size_t(chart_of[f])] + s.normal[f] * s.area[f];
        std::size_t moved = 0;
        for (std::size_t f = 0; f < faces; ++f) {
            if (chart_of[f] < 0) continue;
            int other[3], count = 0;
            for (int k = 0; k < 3; ++k) {
                const int g = s.neighbour[f][k];
                if (g >= 0 && chart_of[std::size_t(g)] != chart_of[f] &&
                    dot(s.normal[f], s.normal[std::size_t(g)]) >= cos_sharp)
                    other[count++] = chart_of[std::size_t(g)];
            }
            int target = -1;
            if (count >= 2 && other[0] == other[1]) target = other[0];
            if (count == 3 && (other[0] == other[2] || other[1] == other[2])) target = other[2];
            if (target < 0 || dot(s.normal[f], normalized(normal_sum[std::size_t(target)])) < cos_cone)
                continue;
            chart_of[f] = target;
            ++moved;
        }
        if (moved == 0) break;
    }
}

// Greedy chart growth: the candidate closest in normal to the chart's mean (then nearest the
// seed) joins while it stays inside the normal cone; sharp edges are never crossed.
constexpr double kDistanceWeight = 0.5;

std::vector<std::vector<int>> grow_charts(const Surface& s, const AtlasOptions& options) {
    const std::size_t faces = s.normal.size();
    const double cos_sharp = std::cos(double(radians(options.sharp_angle)));
    const double cos_cone = std::cos(double(radians(options.cone_angle)));
    std::vector<int> chart_of(faces, -1);
    std::vector<std::vector<int>> charts;
    using Candidate = std::pair<double, int>;
    for (std::size_t seed = 0; seed < faces; ++seed) {
        if (s.degenerate[seed] || chart_of[seed] >= 0) continue;
        const int id = int(charts.size());
        std::vector<int> members;
        D3 normal_sum{};
        std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> queue;
        const auto add = [&](int f) {
            chart_of[std::size_t(f)] = id;
            members.push_back(f);
            normal_sum = normal_sum + s.normal[std::size_t(f)] * s.area[std::size_t(f)];
            const D3 mean = normalized(normal_sum);
            for (int k = 0; k < 3; ++k) {
                const int g = s.neighbour[std::size_t(f)][k];
                if (g < 0 || chart_of[std::size_t(g)] >= 0) continue;
                if (dot(s.normal[std::size_t(f)], s.normal[std::size_t(g)]) < cos_sharp) continue;
                // Normal deviation plus distance to the seed (over the diagonal, weighted
                // kDistanceWeight): among faces of similar normal the nearest joins first, so flat
                // regions grow as compact discs rather than in face order.
                const D3 offset = s.centroid[std::size_t(g)] - s.centroid[seed];
                const double cost = (1.0 - dot(s.normal[std::size_t(g)], mean)) +
                                    kDistanceWeight * std::sqrt(dot(offset, offset)) / s.diagonal;
                queue.emplace(cost, g);
            }
        };
        add(int(seed));
        while (!queue.empty()) {
            const int g = queue.top().second;
            queue.pop();
            if (chart_of[std::size_t(g)] >= 0) continue;
            if (dot(s.normal[std::size_t(g)], normalized(normal_sum)) < cos_cone) continue;
            add(g);
        }
        charts.push_back(std::move(members));
    }
    smooth_chart_borders(s, cos_sharp, cos_cone, chart_of, charts.size());
    for (auto& members : charts) members.clear();
    for (std::size_t f = 0; f < faces; ++f)
        if (chart_of[f] >= 0) charts[std::size_t(chart_of[f])].push_back(int(f));
    charts.erase(
        std::remove_if(charts.begin(), charts.end(), [](const std::vector<int>& c) { return c.empty(); }),
        charts.end());
    return charts;
}

// A flattened chart: UVs in 3-D units (area-true) per local vertex, and per member face the
// local vertices of its corners.
struct FlatChart {
    std::vector<int> faces;
    std::vector<Vec3i> corners;  // per face: local vertex ids
    std::vector<Vec2f> uvs;      // per local vertex
    std::vector<int> vertex_of;  // per local vertex: welded vertex
};

struct FlattenOutcome {
    bool ok = false;
    FlatChart chart;
    std::vector<std::vector<int>> parts;  // when !ok: the pieces to retry
};

// Cuts a chart in two across the longest axis of its face centroids' bounding box.
std::vector<std::vector<int>> split_in_two(const Surface& s, const std::vector<int>& faces) {
    D3 lo = s.centroid[std::size_t(faces[0])], hi = lo;
    for (const int f : faces) {
        const D3 c = s.centroid[std::size_t(f)];
        lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
        hi = {std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z)};
    }
    const D3 e = hi - lo;
    const int axis = (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
    const auto coordinate = [&](int f) {
        const D3 c = s.centroid[std::size_t(f)];
        return axis == 0 ? c.x : (axis == 1 ? c.y : c.z);
    };
    std::vector<int> sorted = faces;
    std::stable_sort(
        sorted.begin(), sorted.end(), [&](int a, int b) { return coordinate(a) < coordinate(b); });
    const auto half = std::ptrdiff_t(sorted.size() / 2);
    std::vector<int> a(sorted.begin(), sorted.begin() + half), b(sorted.begin() + half, sorted.end());
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    return {a, b};
}

enum class ChartCheck { Ok, TooStretched, Invalid };

// A chart filling less of its convex hull than this (a thin arc, a ring with an appendage) wastes
// atlas space around it: it is split. Charts of fewer faces are left alone.
constexpr double kMinHullFill = 0.35;
constexpr std::size_t kMinFacesToSplitSparse = 16;

// Charts up to this size may be re-flattened with ARAP (about 1 s per 20k faces here).
constexpr std::size_t kArapMaxFaces = 20000;

// Un-mirrors a flattened chart that came out clockwise, scales it to its 3-D area, and checks
// it: every triangle counter-clockwise, no self-overlap, L2 stretch within the bound.
ChartCheck orient_scale_and_check(const Surface& s, const std::vector<int>& faces,
                                  const std::vector<Vec3f>& positions, const std::vector<Vec3i>& corners,
                                  const AtlasOptions& options, std::vector<Vec2f>& uvs) {
    double uv_area2 = 0, area3 = 0;
    for (std::size_t i = 0; i < faces.size(); ++i) {
        const Vec3i c = corners[i];
        uv_area2 += signed_uv_area2(uvs[std::size_t(c.x)], uvs[std::size_t(c.y)], uvs[std::size_t(c.z)]);
        area3 += s.area[std::size_t(faces[i])];
    }
    if (!(std::abs(uv_area2) > 0)) return ChartCheck::Invalid;
    if (uv_area2 < 0)
        for (Vec2f& uv : uvs) uv.x = -uv.x;
    const float scale = float(std::sqrt(area3 / (0.5 * std::abs(uv_area2))));
    for (Vec2f& uv : uvs) uv = uv * scale;
    double stretch_sum = 0;
    for (std::size_t i = 0; i < faces.size(); ++i) {
        const Vec3i c = corners[i];
        const std::array<Vec2f, 3> p = {uvs[std::size_t(c.x)], uvs[std::size_t(c.y)], uvs[std::size_t(c.z)]};
        if (!(signed_uv_area2(p[0], p[1], p[2]) > 0)) return ChartCheck::Invalid;
        const std::array<Vec3f, 3> q = {
            positions[std::size_t(c.x)], positions[std::size_t(c.y)], positions[std::size_t(c.z)]};
        stretch_sum += l2_stretch_squared(q, p) * s.area[std::size_t(faces[i])];
    }
    // Ten times stricter than the report's tolerance, so that rounding packed UVs to float
    // cannot turn a pinched border into a reported overlap.
    if (count_overlapping_pairs(uvs, corners, true, 0.1 * kOverlapTolerance) > 0) return ChartCheck::Invalid;
    return std::sqrt(stretch_sum / area3) > double(options.max_stretch) ? ChartCheck::TooStretched
                                                                        : ChartCheck::Ok;
}

FlattenOutcome flatten(const Surface& s, const std::vector<int>& faces, const AtlasOptions& options) {
    FlattenOutcome out;
    const std::size_t n = faces.size();
    std::unordered_map<int, int> slot_of;  // face -> index in `faces`
    slot_of.reserve(n * 2);
    for (std::size_t i = 0; i < n; ++i) slot_of.emplace(faces[i], int(i));

    // Local vertices: corners glued across the chart's internal edges (bow-ties stay apart).
    std::vector<int> parent(n * 3);
    std::iota(parent.begin(), parent.end(), 0);
    std::vector<int> component(n);
    std::iota(component.begin(), component.end(), 0);
    std::size_t internal_halfedges = 0;
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const int g = s.neighbour[std::size_t(faces[i])][k];
            const auto it = g < 0 ? slot_of.end() : slot_of.find(g);
            if (it == slot_of.end()) continue;
            ++internal_halfedges;
            const int j = it->second, l = s.neighbour_edge[std::size_t(faces[i])][k];
            // Edge k of face i runs corner k -> k+1; in face j the same edge runs l+1 -> l.
            const auto unite = [&](int x, int y) {
                parent[std::size_t(find_root(parent, x))] = find_root(parent, y);
            };
            unite(int(i) * 3 + k, j * 3 + (l + 1) % 3);
            unite(int(i) * 3 + (k + 1) % 3, j * 3 + l);
            component[std::size_t(find_root(component, int(i)))] = find_root(component, j);
        }
    // Disconnected pieces (after a split) are flattened separately.
    std::vector<std::vector<int>> pieces;
    std::unordered_map<int, std::size_t> piece_of;
    for (std::size_t i = 0; i < n; ++i) {
        const int root = find_root(component, int(i));
        const auto [it, inserted] = piece_of.emplace(root, pieces.size());
        if (inserted) pieces.emplace_back();
        pieces[it->second].push_back(faces[i]);
    }
    if (pieces.size() > 1) {
        out.parts = std::move(pieces);
        return out;
    }

    FlatChart& chart = out.chart;
    chart.faces = faces;
    chart.corners.resize(n);
    std::unordered_map<int, int> local_of_root;
    std::vector<Vec3f> local_positions;
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const int root = find_root(parent, int(i) * 3 + k);
            const auto [it, inserted] = local_of_root.emplace(root, int(local_positions.size()));
            if (inserted) {
                local_positions.push_back(
                    s.mesh->positions[std::size_t(s.mesh->triangles[std::size_t(faces[i])][k])]);
                chart.vertex_of.push_back(s.vertex(faces[i], k));
            }
            chart.corners[i][k] = it->second;
        }

    if (n == 1) {  // a lone triangle: lay it out exactly
        // Along its longest edge, so a needle with two nearly coincident corners stays exact.
        int k = 0;
        for (int e = 1; e < 3; ++e)
            if (length(local_positions[std::size_t((e + 1) % 3)] - local_positions[std::size_t(e)]) >
                length(local_positions[std::size_t((k + 1) % 3)] - local_positions[std::size_t(k)]))
                k = e;
        const std::size_t i0 = std::size_t(k), i1 = std::size_t((k + 1) % 3), i2 = std::size_t((k + 2) % 3);
        const Vec3f a = local_positions[i0], b = local_positions[i1], c = local_positions[i2];
        const float ab = length(b - a);
        const Vec3f x_axis = (b - a) / ab;
        chart.uvs.assign(3, Vec2f{});
        chart.uvs[i1] = {ab, 0};
        chart.uvs[i2] = {dot(c - a, x_axis), float(2.0 * s.area[std::size_t(faces[0])] / ab)};
        out.ok = true;
        return out;
    }
    const auto fail = [&]() {
        out.parts = split_in_two(s, faces);
        return out;
    };
    // Euler characteristic V - E + F must be 1 for a disk (connected, one border).
    const std::size_t edges = internal_halfedges / 2 + (3 * n - internal_halfedges);
    if (long(local_positions.size()) - long(edges) + long(n) != 1) return fail();
    if (!flatten_chart(local_positions, chart.corners, false, chart.uvs)) return fail();
    ChartCheck check = orient_scale_and_check(s, faces, local_positions, chart.corners, options, chart.uvs);
    // ARAP only where conformal flattening stretches too much: it costs ~3x LSCM per solve.
    if (check == ChartCheck::TooStretched && options.flattening == ChartFlattening::Arap &&
        n <= kArapMaxFaces) {
        std::vector<Vec2f> arap_uvs;
        if (flatten_chart(local_positions, chart.corners, true, arap_uvs) &&
            orient_scale_and_check(s, faces, local_positions, chart.corners, options, arap_uvs) ==
                ChartCheck::Ok) {
            chart.uvs = std::move(arap_uvs);
            check = ChartCheck::Ok;
        }
    }
    if (check != ChartCheck::Ok) return fail();
    if (n >= kMinFacesToSplitSparse) {
        double area = 0;
        for (const Vec3i& c : chart.corners)
            area += 0.5 * signed_uv_area2(chart.uvs[std::size_t(c.x)],
                                          chart.uvs[std::size_t(c.y)],
                                          chart.uvs[std::size_t(c.z)]);
        if (area < kMinHullFill * polygon_area(convex_hull(chart.uvs))) return fail();
    }
    out.ok = true;
    return out;
}

void validate_options(const AtlasOptions& o) {
    if (o.size < 16 || o.size > 16384)
        throw_error("atlas size {} is out of range [16, 16384] texels", o.size);
    if (o.gutter < 0 || o.gutter > 64)
        throw_error("atlas gutter {} is out of range [0, 64] texels", o.gutter);
    if (!(o.sharp_angle > 0 && o.sharp_angle <= 180))
        throw_error("atlas sharp angle {} is out of range (0, 180] degrees", o.sharp_angle);
    if (!(o.cone_angle > 0 && o.cone_angle < 90))
        throw_error("atlas cone angle {} is out of range (0, 90) degrees", o.cone_angle);
    if (!(o.max_stretch >= 1)) throw_error("atlas maximum stretch {} must be at least 1", o.max_stretch);
}

// Every face gets UVs: flattened charts, then zero-area faces glued to a chart they touch (their
// corners reuse its UVs), else a small triangle of their own.
TriangleMesh assemble(const TriangleMesh& mesh, const Surface& s, std::vector<FlatChart>& charts,
                      const AtlasOptions& options) {
    const std::size_t faces = mesh.triangles.size();
    std::vector<int> chart_of(faces, -1), local_of(faces, -1);
    for (std::size_t c = 0; c < charts.size(); ++c)
        for (std::size_t i = 0; i < charts[c].faces.size(); ++i) {
            chart_of[std::size_t(charts[c].faces[i])] = int(c);
            local_of[std::size_t(charts[c].faces[i])] = int(i);
        }
    // (chart, welded vertex) -> local vertex, the first one in chart order.
    std::vector<std::unordered_map<int, int>> vertex_in(charts.size());
    for (std::size_t c = 0; c < charts.size(); ++c)
        for (std::size_t v = 0; v < charts[c].vertex_of.size(); ++v)
            vertex_in[c].emplace(charts[c].vertex_of[v], int(v));

    double mean_area = 0;
    for (const double a : s.area) mean_area += a;
    mean_area /= double(faces);
    std::vector<int> pending;
    for (std::size_t f = 0; f < faces; ++f)
        if (s.degenerate[f]) pending.push_back(int(f));
    // Glue zero-area faces to a chart sharing a vertex; repeat so chains of them attach too.
    for (bool progress = true; progress && !pending.empty();) {
        progress = false;
        std::vector<int> left;
        for (const int f : pending) {
            int chart = -1;
            for (int k = 0; k < 3 && chart < 0; ++k)
                for (std::size_t c = 0; c < charts.size() && chart < 0; ++c)
                    if (vertex_in[c].count(s.vertex(f, k))) chart = int(c);
            if (chart < 0) {
                left.push_back(f);
                continue;
            }
            FlatChart& fc = charts[std::size_t(chart)];
            Vec3i corners{-1, -1, -1};
            int known = -1;
            for (int k = 0; k < 3; ++k) {
                const auto it = vertex_in[std::size_t(chart)].find(s.vertex(f, k));
                if (it != vertex_in[std::size_t(chart)].end()) corners[k] = known = it->second;
            }
            for (int k = 0; k < 3; ++k)
                if (corners[k] < 0) {
                    // A vertex only zero-area faces use: it sits on the face's other corners.
                    corners[k] = int(fc.uvs.size());
                    fc.uvs.push_back(fc.uvs[std::size_t(known)]);
                    fc.vertex_of.push_back(s.vertex(f, k));
                    vertex_in[std::size_t(chart)].emplace(s.vertex(f, k), corners[k]);
                }
            chart_of[std::size_t(f)] = chart;
            local_of[std::size_t(f)] = int(fc.faces.size());
            fc.faces.push_back(f);
            fc.corners.push_back(corners);
            progress = true;
        }
        pending.swap(left);
    }
    for (const int f : pending) {  // isolated zero-area faces: a small triangle each
        FlatChart fc;
        const float side = float(std::sqrt(std::max(mean_area, 1e-30)) * 0.25);
        fc.faces = {f};
        fc.corners = {{0, 1, 2}};
        fc.uvs = {{0, 0}, {side, 0}, {0, side}};
        fc.vertex_of = {s.vertex(f, 0), s.vertex(f, 1), s.vertex(f, 2)};
        chart_of[std::size_t(f)] = int(charts.size());
        local_of[std::size_t(f)] = 0;
        charts.push_back(std::move(fc));
    }

    std::vector<PackChart> packing(charts.size());
    for (std::size_t c = 0; c < charts.size(); ++c) {
        packing[c].uvs = charts[c].uvs;
        packing[c].triangles = charts[c].corners;
    }
    pack_charts(packing, options.size, options.gutter);

    TriangleMesh out = mesh;
    out.uvs.clear();
    std::vector<int> offset(charts.size());
    for (std::size_t c = 0; c < charts.size(); ++c) {
        offset[c] = int(out.uvs.size());
        out.uvs.insert(out.uvs.end(), packing[c].uvs.begin(), packing[c].uvs.end());
    }
    out.uv_triangles.assign(faces, Vec3i{});
    for (std::size_t f = 0; f < faces; ++f) {
        const int c = chart_of[f];
        TDF_CHECK(c >= 0);
        const Vec3i local = charts[std::size_t(c)].corners[std::size_t(local_of[f])];
        out.uv_triangles[f] = {local.x + offset[std::size_t(c)],
                               local.y + offset[std::size_t(c)],
                               local.z + offset[std::size_t(c)]};
    }
    return out;
}

}  // namespace

TriangleMesh build_atlas(const TriangleMesh& mesh, const AtlasOptions& options, AtlasReport* report) {
    const auto start = std::chrono::steady_clock::now();
    validate_options(options);
    if (mesh.triangles.empty())
        throw_error("{}: cannot build a UV atlas for a mesh without faces", mesh.source_path);
    const bool unwrap = options.reunwrap || !mesh.has_uvs();
    TriangleMesh out;
    if (!unwrap) {
        out = mesh;
    } else {
        const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
            return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
        };
        // Progress in fixed stage weights (on a 1M-triangle sphere flattening takes most of
        // the time); flattening advances per batch of charts.
        constexpr std::size_t kSurface = 5, kGrow = 10, kFlatten = 60, kPack = 25;
        // Meshes that unwrap in about a second stay quiet.
        constexpr std::size_t kProgressFaces = 50000;
        std::unique_ptr<ProgressReporter> reporter;
        if (mesh.triangles.size() >= kProgressFaces)
            reporter = std::make_unique<ProgressReporter>("atlas", kSurface + kGrow + kFlatten + kPack, 1);
        const auto advance = [&](std::size_t n, const std::string& status) {
            if (reporter) reporter->advance(n, status);
        };
        const Surface surface = analyse_surface(mesh);
        advance(kSurface, fmt::format("{} faces analysed", mesh.triangles.size()));
        std::vector<std::vector<int>> pending = grow_charts(surface, options);
        advance(kGrow, fmt::format("{} charts grown", pending.size()));
        log_verbose("atlas: {} charts grown in {:.2f} s", pending.size(), seconds_since(start));
        const auto flatten_start = std::chrono::steady_clock::now();
        std::vector<FlatChart> charts;
        // Rounds of parallel flattening; failed charts come back split. Results are collected
        // in list order, so the atlas does not depend on the thread count. Each round runs in
        // batches so that progress moves; a round gets half of the flattening weight still
        // left (the number of rounds is not known in advance: charts that fail come back split).
        std::size_t flatten_credit = kFlatten;
        while (!pending.empty()) {
            const std::size_t round_budget =
                std::max<std::size_t>(flatten_credit / 2, flatten_credit > 0 ? 1 : 0);
            std::size_t round_credit = round_budget;
            std::vector<FlattenOutcome> outcomes(pending.size());
            // Batches of at least 4 charts per thread, so that batching never idles a thread
            // (charts are independent: batching does not change the result).
            constexpr std::size_t kBatches = 20;
            const std::size_t batch =
                std::max<std::size_t>((pending.size() + kBatches - 1) / kBatches,
                                      4 * std::size_t(std::max(1, ThreadLimit::current())));
            for (std::size_t first = 0; first < pending.size(); first += batch) {
                const std::size_t last = std::min(pending.size(), first + batch);
                parallel_for(last - first, 1, [&](std::size_t begin, std::size_t end) {
                    for (std::size_t i = first + begin; i < first + end; ++i)
                        outcomes[i] = flatten(surface, pending[i], options);
                });
                const std::size_t share = round_budget * (last - first) / pending.size();
                const std::size_t step = std::min(round_credit, std::max<std::size_t>(share, 1));
                round_credit -= step;
                flatten_credit -= step;
                advance(step, fmt::format("flattened {}/{} charts", last, pending.size()));
            }
            std::vector<std::vector<int>> next;
            for (FlattenOutcome& o : outcomes) {
                if (o.ok)
                    charts.push_back(std::move(o.chart));
                else
                    for (auto& part : o.parts) next.push_back(std::move(part));
            }
            pending.swap(next);
        }
        advance(flatten_credit, fmt::format("{} charts flattened", charts.size()));
        log_verbose("atlas: {} charts flattened in {:.2f} s", charts.size(), seconds_since(flatten_start));
        const auto pack_start = std::chrono::steady_clock::now();
        out = assemble(mesh, surface, charts, options);
        advance(kPack, "packed");
        if (reporter) reporter->finish();
        log_verbose("atlas: packed in {:.2f} s", seconds_since(pack_start));
        if (out.normals.size() != out.positions.size()) compute_normals(out);
        compute_tangents(out, TangentMode::Handed);
    }
    if (report) {
        *report = measure_atlas(out, options.size);
        report->reunwrapped = unwrap;
        report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return out;
}

}  // namespace tdf
