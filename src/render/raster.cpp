#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/render/raster.h>
#include <tdf/render/trace.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace tdf {

namespace {

struct Vec3d {
    double x = 0, y = 0, z = 0;
};
inline Vec3d cross(const Vec3d& a, const Vec3d& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double dot(const Vec3d& a, const Vec3d& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// A triangle ready for coverage tests. Edge k is E_k(X, Y) = a X + b Y + c in homogeneous pixel
// space (Olano and Greer 1997): E_k = (X, Y, 1) . (v_i x v_j) for the two other vertices, scaled
// by the sign of the determinant so that the inside is where every E_k >= 0 (either winding).
// Then the perspective-correct barycentric of vertex k is E_k / sum(E), and z/w is linear in
// (X, Y): sum(z_k E_k) / |det|.
struct TriangleSetup {
    Vec3d edge[3];
    Vec3d z_plane;
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive pixel bounds; empty when x1 < x0
    bool tie_inside[3] = {};               // E_k == 0 counts as inside (top-left rule)
};

// The top-left rule in image coordinates (row 0 first): a centre exactly on an edge is inside
// when the interior lies to the edge's right (a > 0: a left edge) or, for a horizontal edge,
// below it (a == 0, b > 0: a top edge). A shared edge has exactly negated coefficients in the two
// triangles (the cross products are computed from the same vertex values), so exactly one side
// takes it.
inline bool top_left(const Vec3d& e) { return e.x > 0 || (e.x == 0 && e.y > 0); }

inline bool covers(const TriangleSetup& t, double X, double Y, double e[3]) {
    for (int k = 0; k < 3; ++k) {
        e[k] = t.edge[k].x * X + t.edge[k].y * Y + t.edge[k].z;
        if (e[k] < 0 || (e[k] == 0 && !t.tie_inside[k])) return false;
    }
    return e[0] + e[1] + e[2] > 0;
}

bool setup_triangle(const Vec4f* clip, const Vec3d* hom, const Vec3i& tri, int width, int height,
                    TriangleSetup& t) {
    const Vec4f& c0 = clip[tri.x];
    const Vec4f& c1 = clip[tri.y];
    const Vec4f& c2 = clip[tri.z];
    // Entirely outside one clip plane: nothing to draw.
    auto all = [&](auto outside) { return outside(c0) && outside(c1) && outside(c2); };
    if (all([](const Vec4f& c) { return c.x > c.w; }) || all([](const Vec4f& c) { return c.x < -c.w; }) ||
        all([](const Vec4f& c) { return c.y > c.w; }) || all([](const Vec4f& c) { return c.y < -c.w; }) ||
        all([](const Vec4f& c) { return c.z > c.w; }) || all([](const Vec4f& c) { return c.z < -c.w; }))
        return false;
    const Vec3d& v0 = hom[tri.x];
    const Vec3d& v1 = hom[tri.y];
    const Vec3d& v2 = hom[tri.z];
    t.edge[0] = cross(v1, v2);
    t.edge[1] = cross(v2, v0);
    t.edge[2] = cross(v0, v1);
    const double det = dot(v0, t.edge[0]);
    if (!(det != 0) || !std::isfinite(det)) return false;  // degenerate in screen space (or NaN input)
    if (det < 0)
        for (auto& e : t.edge) e = {-e.x, -e.y, -e.z};
    const double inv = 1.0 / std::fabs(det);
    t.z_plane = {};
    const double z[3] = {c0.z, c1.z, c2.z};
    for (int k = 0; k < 3; ++k) {
        t.z_plane.x += z[k] * t.edge[k].x * inv;
        t.z_plane.y += z[k] * t.edge[k].y * inv;
        t.z_plane.z += z[k] * t.edge[k].z * inv;
        t.tie_inside[k] = top_left(t.edge[k]);
    }
    // Pixel bounds: the projected vertices when all are in front of the camera plane, else the
    // whole image (the edge functions still clip exactly).
    t.x0 = 0, t.y0 = 0, t.x1 = width - 1, t.y1 = height - 1;
    if (c0.w > 0 && c1.w > 0 && c2.w > 0) {  // NaN-free: the mesh loaders reject non-finite input
        double lo_x = std::numeric_limits<double>::max(), hi_x = -lo_x, lo_y = lo_x, hi_y = -lo_x;
        for (const Vec3d* v : {&v0, &v1, &v2}) {
            const double X = v->x / v->z, Y = v->y / v->z;
            lo_x = std::min(lo_x, X), hi_x = std::max(hi_x, X);
            lo_y = std::min(lo_y, Y), hi_y = std::max(hi_y, Y);
        }
        // Centres j + 0.5 inside [lo, hi], widened to whole pixels outward (floor / ceil), which
        // absorbs the rounding of the division; the edge functions decide exactly.
        // Clamped on both sides before the int conversion (projections can be huge).
        auto lo = [](double v, int n) { return int(std::clamp(std::floor(v - 0.5), 0.0, double(n))); };
        auto hi = [](double v, int n) { return int(std::clamp(std::ceil(v - 0.5), -1.0, double(n - 1))); };
        t.x0 = lo(lo_x, width), t.x1 = hi(hi_x, width);
        t.y0 = lo(lo_y, height), t.y1 = hi(hi_y, height);
    }
    return t.x0 <= t.x1 && t.y0 <= t.y1;
}

constexpr std::size_t kSetupChunk = 4096;

// Per chunk of triangles, the visible ones grouped by tile in triangle order (CSR layout).
struct ChunkBins {
    std::vector<std::uint32_t> offsets;  // tiles + 1
    std::vector<std::uint32_t> ids;
};

}  // namespace

std::vector<Vec4f> clip_positions(const TriangleMesh& mesh, const Camera& camera) {
    const Mat4f view = camera.view_matrix();
    const Mat4f projection = camera.projection_matrix();
    std::vector<Vec4f> clip(mesh.positions.size());
    parallel_for(clip.size(), 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const Vec3f& p = mesh.positions[i];
            clip[i] = projection * (view * Vec4f{p.x, p.y, p.z, 1.f});
        }
    });
    return clip;
}

void rasterize(const std::vector<Vec4f>& clip, const std::vector<Vec3i>& triangles, int width, int height,
               RasterBuffer& out) {
    if (width <= 0 || height <= 0)
        throw_error("image size {}x{} is empty (width and height must be positive)", width, height);
    const int n_vertices = int(clip.size());
    for (const Vec3i& t : triangles)
        if (t.x < 0 || t.y < 0 || t.z < 0 || t.x >= n_vertices || t.y >= n_vertices || t.z >= n_vertices)
            throw_error(
                "rasterize: triangle ({}, {}, {}) indexes past {} vertices", t.x, t.y, t.z, n_vertices);
    out.width = width;
    out.height = height;
    const std::size_t n = std::size_t(width) * std::size_t(height);
    out.rast.resize(n);
    out.rast_db.resize(n);

    // Homogeneous pixel coordinates (X w, Y w, w) of every vertex, computed once so shared edges
    // see bit-identical values: X = (x/w + 1) W/2 puts pixel centres at j + 0.5.
    std::vector<Vec3d> hom(clip.size());
    const double hw = 0.5 * width, hh = 0.5 * height;
    parallel_for(clip.size(), 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const Vec4f& c = clip[i];
            hom[i] = {(double(c.x) + double(c.w)) * hw, (double(c.y) + double(c.w)) * hh, double(c.w)};
        }
    });

    const int tiles_x = int(chunk_count(std::size_t(width), kRasterTile));
    const int tiles_y = int(chunk_count(std::size_t(height), kRasterTile));
    const std::size_t n_tiles = std::size_t(tiles_x) * std::size_t(tiles_y);
    std::vector<TriangleSetup> setups(triangles.size());
    std::vector<std::uint8_t> visible(triangles.size());
    std::vector<ChunkBins> chunks(chunk_count(triangles.size(), kSetupChunk));
    parallel_for(chunks.size(), 1, [&](std::size_t cb, std::size_t ce) {
        for (std::size_t c = cb; c < ce; ++c) {
            const std::size_t t0 = c * kSetupChunk, t1 = std::min(triangles.size(), t0 + kSetupChunk);
            ChunkBins& bins = chunks[c];
            bins.offsets.assign(n_tiles + 1, 0);
            for (std::size_t t = t0; t < t1; ++t) {
                visible[t] = setup_triangle(clip.data(), hom.data(), triangles[t], width, height, setups[t]);
                if (!visible[t]) continue;
                const TriangleSetup& s = setups[t];
                for (int ty = s.y0 / kRasterTile; ty <= s.y1 / kRasterTile; ++ty)
                    for (int tx = s.x0 / kRasterTile; tx <= s.x1 / kRasterTile; ++tx)
                        ++bins.offsets[std::size_t(ty * tiles_x + tx) + 1];
            }
            for (std::size_t k = 0; k < n_tiles; ++k) bins.offsets[k + 1] += bins.offsets[k];
            bins.ids.resize(bins.offsets[n_tiles]);
            std::vector<std::uint32_t> fill(bins.offsets.begin(), bins.offsets.end() - 1);
            for (std::size_t t = t0; t < t1; ++t) {
                if (!visible[t]) continue;
                const TriangleSetup& s = setups[t];
                for (int ty = s.y0 / kRasterTile; ty <= s.y1 / kRasterTile; ++ty)
                    for (int tx = s.x0 / kRasterTile; tx <= s.x1 / kRasterTile; ++tx)
                        bins.ids[fill[std::size_t(ty * tiles_x + tx)]++] = std::uint32_t(t);
            }
        }
    });

    parallel_for_tiles(width, height, kRasterTile, [&](int x0, int y0, int x1, int y1) {
        const int tw = x1 - x0;
        const std::size_t tile = std::size_t((y0 / kRasterTile) * tiles_x + x0 / kRasterTile);
        float depth[kRasterTile * kRasterTile];
        int winner[kRasterTile * kRasterTile];
        std::fill(depth, depth + kRasterTile * kRasterTile, std::numeric_limits<float>::infinity());
        std::fill(winner, winner + kRasterTile * kRasterTile, -1);
        double e[3];
        for (const ChunkBins& bins : chunks) {
            for (std::uint32_t k = bins.offsets[tile]; k < bins.offsets[tile + 1]; ++k) {
                const int t = int(bins.ids[k]);
                const TriangleSetup& s = setups[std::size_t(t)];
                const int px0 = std::max(x0, s.x0), px1 = std::min(x1 - 1, s.x1);
                const int py0 = std::max(y0, s.y0), py1 = std::min(y1 - 1, s.y1);
                for (int y = py0; y <= py1; ++y) {
                    const double Y = double(y) + 0.5;
                    for (int x = px0; x <= px1; ++x) {
                        const double X = double(x) + 0.5;
                        if (!covers(s, X, Y, e)) continue;
                        const double zd = s.z_plane.x * X + s.z_plane.y * Y + s.z_plane.z;
                        if (!(zd >= -1.0 && zd <= 1.0)) continue;  // near / far planes (-w <= z <= w)
                        const float z = float(zd);
                        const int i = (y - y0) * tw + (x - x0);
                        if (z < depth[i]) {
                            depth[i] = z;
                            winner[i] = t;
                        }
                    }
                }
            }
        }
        // Resolve the winners: barycentrics and their analytic screen-space derivatives.
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const int i = (y - y0) * tw + (x - x0);
                const std::size_t o = out.index(x, y);
                const int t = winner[i];
                if (t < 0) {
                    out.rast[o] = {0, 0, 0, 0};
                    out.rast_db[o] = {0, 0, 0, 0};
                    continue;
                }
                const TriangleSetup& s = setups[std::size_t(t)];
                const double X = double(x) + 0.5, Y = double(y) + 0.5;
                for (int k = 0; k < 3; ++k) e[k] = s.edge[k].x * X + s.edge[k].y * Y + s.edge[k].z;
                const double sum = e[0] + e[1] + e[2];
                const double inv = 1.0 / sum;
                const double u = e[0] * inv, v = e[1] * inv;
                // d(E_k / S)/dX = (a_k - b_k A) / S with A = sum a (the same for Y).
                const double ax = s.edge[0].x + s.edge[1].x + s.edge[2].x;
                const double ay = s.edge[0].y + s.edge[1].y + s.edge[2].y;
                out.rast[o] = {float(u), float(v), depth[i], float(t + 1)};
                out.rast_db[o] = {float((s.edge[0].x - u * ax) * inv),
                                  float((s.edge[0].y - u * ay) * inv),
                                  float((s.edge[1].x - v * ax) * inv),
                                  float((s.edge[1].y - v * ay) * inv)};
            }
    });
}

namespace {

// dr.interpolate of the pixels [x0, x1) x [y0, y1) into out.index(x - ox, y - oy).
void interpolate_region(const RasterBuffer& raster, const TriangleMesh& mesh, const Camera& camera, int x0,
                        int y0, int x1, int y1, GBuffer& tile, int ox, int oy) {
    const bool has_tangents = !mesh.tangents.empty();
    const bool has_uvs = mesh.has_uvs();
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const std::size_t i = tile.index(x - ox, y - oy);
            const std::size_t o = raster.index(x, y);
            const int f = raster.triangle(o);
            if (f < 0) {
                tile.clear_pixel(i);
                continue;
            }
            // dr.interpolate: out = b0 a0 + b1 a1 + b2 a2 with b2 = 1 - u - v, in float32.
            const Vec4f r = raster.rast[o];
            const float b0 = r.x, b1 = r.y, b2 = 1.f - r.x - r.y;
            const Vec3i& tri = mesh.triangles[std::size_t(f)];
            tile.mask[i] = 1.f;
            tile.triangle[i] = f;
            tile.barycentric[i] = {b1, b2};
            const Vec3f p = mesh.positions[std::size_t(tri.x)] * b0 +
                            mesh.positions[std::size_t(tri.y)] * b1 + mesh.positions[std::size_t(tri.z)] * b2;
            tile.position[i] = p;
            tile.depth[i] = -dot(camera.back, p - camera.position);
            tile.normal[i] =
                safe_normalize(mesh.normals[std::size_t(tri.x)] * b0 + mesh.normals[std::size_t(tri.y)] * b1 +
                               mesh.normals[std::size_t(tri.z)] * b2);
            if (has_tangents) {
                const Vec3i& tt = mesh.tangent_triangles[std::size_t(f)];
                const Vec4f& t0 = mesh.tangents[std::size_t(tt.x)];
                const Vec4f& t1 = mesh.tangents[std::size_t(tt.y)];
                const Vec4f& t2 = mesh.tangents[std::size_t(tt.z)];
                const Vec3f tw = t0.xyz() * b0 + t1.xyz() * b1 + t2.xyz() * b2;
                const float w = t0.w * b0 + t1.w * b1 + t2.w * b2;
                tile.tangent[i] = safe_normalize(tw);
                tile.handedness[i] = w < 0.f ? -1.f : 1.f;
            } else {
                tile.tangent[i] = {};
                tile.handedness[i] = 1.f;
            }
            if (has_uvs) {
                const Vec3i& ut = mesh.uv_triangles[std::size_t(f)];
                const Vec2f uv0 = mesh.uvs[std::size_t(ut.x)], uv1 = mesh.uvs[std::size_t(ut.y)],
                            uv2 = mesh.uvs[std::size_t(ut.z)];
                tile.uv[i] = uv0 * b0 + uv1 * b1 + uv2 * b2;
                const Vec4f db = raster.rast_db[o];
                const Vec2f ds_du = uv0 - uv2, ds_dv = uv1 - uv2;
                tile.duv_dx[i] = ds_du * db.x + ds_dv * db.z;
                tile.duv_dy[i] = ds_du * db.y + ds_dv * db.w;
            } else {
                tile.uv[i] = tile.duv_dx[i] = tile.duv_dy[i] = {};
            }
        }
}

}  // namespace

void interpolate_tile(const RasterBuffer& raster, const TriangleMesh& mesh, const Camera& camera, int x0,
                      int y0, int x1, int y1, GBuffer& tile) {
    TDF_CHECK(x0 >= 0 && y0 >= 0 && x1 <= raster.width && y1 <= raster.height && x0 < x1 && y0 < y1);
    TDF_CHECK_EQ(mesh.normals.size(), mesh.positions.size());
    if (tile.width != x1 - x0 || tile.height != y1 - y0) tile.resize(x1 - x0, y1 - y0);
    interpolate_region(raster, mesh, camera, x0, y0, x1, y1, tile, x0, y0);
}

void raster_gbuffer(const TriangleMesh& mesh, const Camera& camera, GBuffer& out) {
    RasterBuffer raster;
    rasterize(clip_positions(mesh, camera), mesh.triangles, camera.width, camera.height, raster);
    TDF_CHECK_EQ(mesh.normals.size(), mesh.positions.size());
    out.resize(camera.width, camera.height);
    // The tracer's tiles (trace.h): a full-frame G-buffer is bound by its writes, which 64x4 tiles keep
    // on few pages.
    parallel_for_tiles(camera.width, camera.height, kTraceTileWidth, kTraceTileHeight,
                       [&](int x0, int y0, int x1, int y1) {
                           interpolate_region(raster, mesh, camera, x0, y0, x1, y1, out, 0, 0);
                       });
}

}  // namespace tdf
