#pragma once
/// Small procedural meshes with UVs for tests, benchmarks and the shipped example scene.
/// Both come back finished like a loaded mesh: validated, normals and tangents computed.
#include <tdf/mesh/triangle_mesh.h>

namespace tdf {

/// A square in the plane z = 0 spanning [-half_size, half_size]^2, facing +Z (counter-clockwise
/// seen from +Z), UVs (0,0) at the lower-left corner to (1,1) at the upper right (u along +X,
/// v along +Y). Two triangles.
TriangleMesh make_quad(float half_size = 1.f, TangentMode tangents = TangentMode::Handed);

/// A UV sphere about the origin: `segments` around the Y axis, `rings` from pole to pole.
/// Positions are shared across the UV seam (u = 0 and u = 1 use separate UV vertices), so
/// normals are smooth everywhere. u grows with azimuth (atan2(x, z) / 2 pi + 0.5), v from the
/// south pole (0) to the north pole (1). 2 segments (rings - 1) triangles.
TriangleMesh make_uv_sphere(float radius, int segments, int rings, TangentMode tangents = TangentMode::Handed);

}  // namespace tdf
