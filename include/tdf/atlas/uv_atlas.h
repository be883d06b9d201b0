#pragma once
/// Automatic UV atlas: charts, CGAL flattening, packing into one square texture.
///
/// Pipeline (src/atlas/uv_atlas.cpp):
///  1. Weld duplicate vertices (within 1e-6 of the bounding-box diagonal) to find adjacency.
///     Edges with more than two faces or with inconsistently oriented faces are seams (the
///     non-manifold edge is split), as are "sharp" edges (dihedral angle > `sharp_angle`).
///  2. Grow charts from seeds over the remaining edges, always taking the candidate face whose
///     normal is closest to the chart's mean normal (plus a small pull toward the seed), stopping
///     at a normal-cone bound (`cone_angle`); then smooth saw-toothed chart borders. This keeps
///     charts nearly developable.
///  3. Flatten each chart with CGAL (LSCM; with ChartFlattening::Arap, ARAP when LSCM stretches
///     too much), then check it: a topological disk, every triangle counter-clockwise (a chart
///     that comes out clockwise is un-mirrored by flipping u; a mix is rejected), no
///     self-overlap, L2 stretch within `max_stretch`, and at least 35 % of its convex hull
///     filled (thin arcs waste atlas space). A chart that fails is cut in two across its longest
///     axis and retried, down to single triangles, which always succeed. Charts are scaled to
///     their true 3-D area, so texel density is uniform.
///  4. Zero-area faces join a chart they touch (their corners take the UVs of coincident chart
///     vertices) or, when isolated, get a tiny chart of their own: every face is mapped.
///  5. Pack (pack_charts): each chart is turned to its minimal-area bounding rectangle,
///     rasterized conservatively at the candidate scale, dilated by half the gutter, and placed
///     at the lowest free position of a texel bitmap over four quarter turns (never a
///     reflection). A search over the scale finds the largest at which every chart fits.
/// Output faces and position indices are the input's (only `uvs`/`uv_triangles` and tangents
/// change), so per-face data and bakes carry over.
#include <tdf/mesh/triangle_mesh.h>

#include <cstddef>
#include <string>

namespace tdf {

enum class ChartFlattening {
    Lscm,  ///< least-squares conformal maps only (fast; preserves angles, may scale areas)
    /// LSCM, then, for a chart whose LSCM stretch exceeds the bound (and that has at most 20k
    /// faces), CGAL ARAP (initialised with LSCM, closer to isometric) before splitting it
    Arap,
};

struct AtlasOptions {
    int size = 1024;            ///< atlas side in texels, [16, 16384]
    int gutter = 4;             ///< minimum empty texels between charts, [0, 64]
    bool reunwrap = false;      ///< replace existing UVs (a mesh without UVs is always unwrapped)
    float sharp_angle = 70.0f;  ///< degrees: dihedral angles above this always cut, (0, 180]
    float cone_angle = 70.0f;   ///< degrees: largest face-normal deviation from a chart's mean, (0, 90)
    float max_stretch = 1.02f;  ///< per-chart L2 stretch bound (1 = isometric), >= 1
    /// LSCM by default: with the tight stretch bound it gives lower stretch and better packing
    /// than ARAP on the shared meshes (smaller charts pack tighter), and is 2-4x faster.
    ChartFlattening flattening = ChartFlattening::Lscm;
};

/// Quality of a UV layout (measure_atlas), plus what build_atlas did.
struct AtlasReport {
    int size = 0;  ///< atlas side used for utilisation
    std::size_t faces = 0;
    std::size_t chart_count = 0;        ///< connected components of the UV layout
    double utilisation = 0;             ///< fraction of texel centres covered by a triangle, [0, 1]
    double stretch_mean = 0;            ///< Sander et al. 2001 L2 stretch over the mesh (1 = isometric)
    double stretch_max = 0;             ///< largest per-triangle L2 stretch (same normalization)
    double angle_distortion_mean = 0;   ///< degrees, mean |UV angle - 3-D angle| over corners
    double angle_distortion_max = 0;    ///< degrees
    std::size_t overlaps = 0;           ///< pairs of UV triangles whose interiors overlap
    std::size_t mirrored_charts = 0;    ///< charts with negative total UV area (wound clockwise)
    std::size_t flipped_triangles = 0;  ///< non-degenerate faces with negative UV area
    /// Faces with non-finite UVs or UVs outside [0,1], or with no UV area although their 3-D
    /// area would cover 1e-3 texel or more at the layout's mean density.
    std::size_t unmapped_faces = 0;
    std::size_t degenerate_faces = 0;  ///< zero-area faces (mapped, left out of the distortion)
    bool reunwrapped = false;          ///< false when the mesh's own UVs were kept
    double seconds = 0;                ///< wall time of build_atlas (0 for measure_atlas alone)
};

/// Builds (or keeps) the UV atlas of `mesh`: returns a copy whose `uvs`/`uv_triangles` come from
/// the pipeline above, with tangents recomputed (TangentMode::Handed). UVs are kept as they are
/// when the mesh has them and `options.reunwrap` is false. Fills `report` (measure_atlas of the
/// result, plus timing) when given. Throws tdf::Error for options out of range or a mesh without
/// faces; never fails on bad geometry (degenerate, non-manifold, duplicated faces).
/// Deterministic: the same input gives the same atlas on any thread count.
TriangleMesh build_atlas(const TriangleMesh& mesh, const AtlasOptions& options,
                         AtlasReport* report = nullptr);

/// Measures any UV layout (see AtlasReport); `size` is the texture side for utilisation.
/// Throws tdf::Error when the mesh has no UVs.
AtlasReport measure_atlas(const TriangleMesh& mesh, int size);

/// Number of pairs of UV triangles whose interiors overlap (count_overlapping_pairs: touching
/// edges and corners do not count, nor depths below kOverlapTolerance of the pair's size;
/// zero-area UV triangles are ignored).
std::size_t count_uv_overlaps(const TriangleMesh& mesh);

/// The report as a JSON object (keys as in AtlasReport).
std::string atlas_report_json(const AtlasReport& report);
/// The report as a few human-readable lines.
std::string format_atlas_report(const AtlasReport& report);

}  // namespace tdf
