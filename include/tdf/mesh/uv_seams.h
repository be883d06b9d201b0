#pragma once
/// How a mesh's UV layout continues across its edges: the faces that share each position edge,
/// and whether their UVs agree there. One implementation for the tangent frames (which share a
/// frame across translation seams), the seam measure of the run reports and the tactile map's
/// cross-fade across seams.
#include <tdf/mesh/triangle_mesh.h>

#include <vector>

namespace tdf {

/// Two faces that share a position edge. `corner_lo[i]` / `corner_hi[i]` are the corners
/// (0..2) of face[i] at the edge's smaller / larger position index.
struct SharedEdge {
    int face[2];
    int corner_lo[2];
    int corner_hi[2];
};

/// Every pair of faces sharing a position edge (an edge of k faces gives k(k-1)/2 pairs), ordered
/// by (smaller position, larger position, faces): the same order on every run.
std::vector<SharedEdge> shared_edges(const TriangleMesh& mesh);

/// How the surface continues between two triangles:
/// - `Same`: a triangle with itself;
/// - `Continuous`: they share a position edge and both its corners' UVs (one chart);
/// - `Seam`: both shared corners have other UVs on each side (a chart boundary, like a sphere's
///   u = 0/1 meridian or the cut between two atlas charts);
/// - `Cone`: one shared corner keeps its UV and the other does not (a UV singularity, such as
///   the fan of a sphere's pole, where one surface point has a different UV in every triangle);
/// - `Apart`: they share no edge.
/// UVs are compared by value (a file may repeat a `vt` line); a mesh without UVs is continuous.
enum class EdgeContinuity { Same, Continuous, Seam, Cone, Apart };
EdgeContinuity uv_continuity(const TriangleMesh& mesh, const SharedEdge& edge);

/// The UV chart of every face: faces joined through Continuous edges share a number (0, 1, ...
/// in order of their first face).
std::vector<int> uv_charts(const TriangleMesh& mesh, const std::vector<SharedEdge>& edges);

/// The UV of corner `corner` (0..2) of face `face`.
inline Vec2f corner_uv(const TriangleMesh& mesh, int face, int corner) {
    return mesh.uvs[std::size_t(mesh.uv_triangles[std::size_t(face)][corner])];
}

}  // namespace tdf
