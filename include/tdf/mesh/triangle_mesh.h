#pragma once
/// The triangle mesh every stage works on.
///
/// Like the reference (spec 1.2) positions and UVs have separate index buffers, so a UV seam
/// does not split the surface: `triangles` index `positions` (the reference's `f`) and
/// `uv_triangles` index `uvs` (`ft`). UVs are stored in the OBJ/glTF-agnostic OBJ convention:
/// u to the right, v UP (v = 0 is the bottom row of a texture image). The reference's internal
/// v' = 1 - v appears only where we match its outputs (the `uv` pass, spec 3.9).
#include <tdf/core/image.h>
#include <tdf/core/vec.h>

#include <array>
#include <string>
#include <vector>

namespace tdf {

/// Where a run of faces came from in the input file: an OBJ object / group / material, or a glTF
/// node + mesh + primitive + material. Exporters keep this structure (a GLB written back has the
/// input's nodes and meshes) and multi-part texturing can take its parts from it.
struct FaceGroup {
    std::string object;    ///< OBJ `o` name, or the glTF node's name
    std::string group;     ///< OBJ `g` name, or the glTF mesh's name
    std::string material;  ///< OBJ `usemtl` name, or the glTF material's name
    int gltf_node = -1;       ///< index in the input's `nodes`; -1 for OBJ/PLY
    int gltf_mesh = -1;       ///< index in the input's `meshes`
    int gltf_primitive = -1;  ///< index in that mesh's `primitives`
    int gltf_material = -1;   ///< index in the input's `materials`
    /// The node's world matrix (column-major, as glTF stores it) that the loader applied to the
    /// positions; identity for OBJ/PLY. An exporter that writes the node back un-applies it.
    std::array<double, 16> world_from_node{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

struct TriangleMesh {
    std::vector<Vec3f> positions;     ///< per position vertex, scene units
    std::vector<Vec3i> triangles;     ///< indices into positions, counter-clockwise = front
    std::vector<Vec2f> uvs;           ///< texture coordinates (OBJ convention, v up)
    std::vector<Vec3i> uv_triangles;  ///< indices into uvs; empty when the mesh has no UVs
    std::vector<Vec3f> colors;        ///< per position vertex colour in [0,1]; empty when none
    std::vector<Vec3f> normals;       ///< per position vertex unit normal (compute_normals)
    /// Per-corner tangent frame (compute_tangents): `tangents[tangent_triangles[f][k]]` is the
    /// unit tangent dP/du at corner k of face f, w = handedness (+1, or -1 on a mirrored chart).
    std::vector<Vec4f> tangents;
    std::vector<Vec3i> tangent_triangles;

    /// Input structure: `face_group[f]` indexes `face_groups` for triangle f. Both empty when the
    /// input had no structure (one group).
    std::vector<FaceGroup> face_groups;
    std::vector<int> face_group;

    Image albedo;              ///< base colour texture (RGB or RGBA), may be empty
    std::string albedo_path;   ///< where `albedo` came from, for messages and exports
    std::string source_path;   ///< the file the mesh was loaded from

    bool has_uvs() const { return !uv_triangles.empty(); }
    bool has_colors() const { return !colors.empty(); }
    std::size_t triangle_count() const { return triangles.size(); }
};

/// Axis-aligned bounds of the positions.
struct Bounds3 {
    Vec3f lower{0, 0, 0};
    Vec3f upper{0, 0, 0};
    Vec3f extent() const { return upper - lower; }
    Vec3f center() const { return (upper + lower) * 0.5f; }
};
Bounds3 compute_bounds(const TriangleMesh& mesh);

/// Area-weighted vertex normals exactly as the reference's `auto_normal` (spec 1.2): face
/// cross products summed into the corners by position index; a sum with squared length
/// <= 1e-20 becomes (0,0,1); then normalized. File normals are never used.
void compute_normals(TriangleMesh& mesh);

enum class TangentMode {
    /// Default: tangents accumulated per (position, uv) corner pair, so charts that meet at a
    /// seam keep their own tangent, with handedness w = -1 on mirrored charts (the shading
    /// normal then flips its bitangent term and mirrored charts shade correctly). Like MikkTSpace,
    /// corners are also split by handedness, so the two sides of a mirror line that share their
    /// UVs keep opposite tangents instead of averaging them away.
    Handed,
    /// The reference (spec 3.3): accumulated per position index, averaged by face count,
    /// handedness discarded (w = +1). Offered for parity with its renders.
    Reference,
};
/// Tangents from positions, UVs and normals (spec 3.3). Needs UVs; without them every
/// tangent is built from the normal alone (any perpendicular unit vector, w = +1).
void compute_tangents(TriangleMesh& mesh, TangentMode mode = TangentMode::Handed);

/// Centres the bounding box on the origin and scales the largest side to 2 * `bound`
/// (the visualizer's `resize=True`, bound 0.9, spec 3.9).
void normalize_mesh(TriangleMesh& mesh, float bound = 0.9f);

/// Checks a loaded mesh and throws tdf::Error naming `source` on: no triangles, indices out
/// of range, non-finite positions/UVs/colours, `face_group` not matching the faces or out of
/// range of `face_groups`, every triangle degenerate. Degenerate
/// (zero-area) triangles among good ones are kept (they are never hit and carry no area) and
/// counted in the returned number so the caller can warn.
std::size_t validate_mesh(const TriangleMesh& mesh, const std::string& source);

}  // namespace tdf
