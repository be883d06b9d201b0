#pragma once
/// Mesh files. Every loader returns a validated mesh with normals and tangents computed
/// (spec 1.2, 3.3), and throws tdf::Error with one line naming the file (and line) on bad input.
#include <tdf/mesh/triangle_mesh.h>

#include <string>

namespace tdf {

struct MeshLoadOptions {
    TangentMode tangent_mode = TangentMode::Handed;
    bool load_textures = true;  ///< read the albedo texture named by the material
};

/// Loads .obj, .gltf, .glb or .ply by extension.
TriangleMesh load_mesh(const std::string& path, const MeshLoadOptions& options = {});

/// Wavefront OBJ: `v x y z [r g b]`, `vt`, `f` with v, v/vt, v/vt/vn, v//vn corners,
/// polygons (fan from the first corner), negative (relative) indices, `mtllib` with
/// `map_Kd` (the last one wins). A missing .mtl or texture is a warning, not an error.
/// `o`, `g` and `usemtl` fill `face_groups` / `face_group` (one group per distinct (o, g, usemtl)
/// triple that has faces, in order of first use); a file with none of them leaves both empty.
TriangleMesh load_obj(const std::string& path, const MeshLoadOptions& options = {});
/// glTF 2.0 (.gltf with .bin, or .glb): POSITION, NORMAL (ignored, recomputed), TEXCOORD_0,
/// COLOR_0, material baseColorTexture; every triangle primitive of every mesh node. Each
/// (node, primitive) with faces becomes one FaceGroup: node name, mesh name, material name, the
/// indices, and the node's world matrix that was applied to its positions.
TriangleMesh load_gltf(const std::string& path, const MeshLoadOptions& options = {});
/// PLY (ASCII and binary): vertex x y z, optional red green blue (uchar or float), optional
/// s t / u v / texture_u texture_v; face vertex_indices (polygons fanned). PLY has no groups:
/// `face_groups` / `face_group` stay empty (one implicit group).
TriangleMesh load_ply(const std::string& path, const MeshLoadOptions& options = {});

/// Finishes a freshly parsed mesh: validates it (warning about degenerate triangles),
/// computes normals and tangents. Loaders call this last.
void finish_loaded_mesh(TriangleMesh& mesh, const std::string& source, const MeshLoadOptions& options);

}  // namespace tdf
