#pragma once
/// Per-triangle measures of a UV map, shared by the atlas builder (chart checks) and its report.
#include <tdf/core/vec.h>

#include <array>
#include <cstddef>
#include <vector>

namespace tdf {

/// Twice the signed area of the UV triangle (a, b, c); positive = counter-clockwise (u right,
/// v up), which for a front-facing triangle means "not mirrored".
inline double signed_uv_area2(Vec2f a, Vec2f b, Vec2f c) {
    return (double(b.x) - a.x) * (double(c.y) - a.y) - (double(b.y) - a.y) * (double(c.x) - a.x);
}

/// Area of the 3-D triangle (a, b, c), computed in double.
double triangle_area(Vec3f a, Vec3f b, Vec3f c);

/// The squared L2 stretch of Sander et al. 2001 of the map from UV to 3-D on one triangle:
/// (|dq/du|^2 + |dq/dv|^2) / 2, which is 1 for an isometry. Infinite for a zero-area UV triangle.
/// Scale-dependent: multiply by (total UV area / total 3-D area) to compare layouts.
double l2_stretch_squared(const std::array<Vec3f, 3>& q, const std::array<Vec2f, 3>& p);

/// Largest |UV angle - 3-D angle| over the triangle's three corners, and their sum, in degrees.
struct AngleDistortion {
    double max = 0;
    double sum = 0;
};
AngleDistortion angle_distortion(const std::array<Vec3f, 3>& q, const std::array<Vec2f, 3>& p);

/// True when the triangle (xs[k], ys[k]) and the axis-aligned box [x0, x1] x [y0, y1] touch,
/// boundaries included (separating axes: the box's two and the triangle's three edge normals).
bool triangle_touches_box(const double (&xs)[3], const double (&ys)[3], double x0, double y0, double x1,
                          double y1);

/// Convex hull of `points`, counter-clockwise (Andrew's monotone chain, in double precision);
/// fewer than 3 points when they are all collinear or coincide.
std::vector<Vec2f> convex_hull(std::vector<Vec2f> points);

/// Area of a simple polygon given counter-clockwise (negative when clockwise).
double polygon_area(const std::vector<Vec2f>& polygon);

/// Relative overlap depth below which two UV triangles count as touching, not overlapping:
/// 1e-4 of the pair's size (a ten-thousandth of a texel for texel-sized triangles). It absorbs
/// the float rounding of packed UVs where a chart's border pinches at a vertex.
constexpr double kOverlapTolerance = 1e-4;

/// Pairs among `triangles` (indices into `uvs`) whose UV interiors overlap by more than
/// `tolerance` times their size: an exact separating-axis test in double precision over the 6
/// edge normals, with a uniform grid for candidate pairs, so sharing an edge or a corner does
/// not count. Zero-area and non-finite triangles are skipped. With `stop_at_first`, returns as
/// soon as one pair is found (0 or 1).
std::size_t count_overlapping_pairs(const std::vector<Vec2f>& uvs, const std::vector<Vec3i>& triangles,
                                    bool stop_at_first = false, double tolerance = kOverlapTolerance);

}  // namespace tdf
