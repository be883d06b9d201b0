#pragma once
/// Flattening one chart with CGAL (the only place tdf includes CGAL: its headers cost ~30 s of
/// compile time, so they stay in src/atlas/chart_parameterization.cpp).
#include <tdf/core/vec.h>

#include <vector>

namespace tdf {

/// Flattens one chart with a free border: the least-squares conformal map (Lévy et al. 2002;
/// CGAL `LSCM_parameterizer_3`, two pinned vertices) or, with `arap`, CGAL's
/// as-rigid-as-possible map (Liu et al. 2008; `ARAP_parameterizer_3`, lambda 1000 = nearly
/// rigid, LSCM start, at most 30 local/global iterations; LSCM when ARAP fails). Input: `positions` and
/// `triangles` index a connected, consistently oriented, manifold triangle mesh that is a topological disk
/// (one border loop, V - E + F = 1) with no zero-area triangles. On success fills `uvs` (one per position, in
/// arbitrary units and orientation: the caller normalizes scale and fixes mirroring) and
/// returns true; returns false when the chart cannot be built as a surface mesh or the solver
/// fails, so the caller can split the chart and retry.
bool flatten_chart(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& triangles, bool arap,
                   std::vector<Vec2f>& uvs);

}  // namespace tdf
