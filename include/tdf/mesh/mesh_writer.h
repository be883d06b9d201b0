#pragma once
/// Mesh files out: Wavefront OBJ + MTL, and binary glTF 2.0 (.glb) with embedded PNG maps.
/// Both are written atomically (temporary name, then rename) and throw tdf::Error naming the
/// file when they cannot be written.
#include <tdf/core/image.h>
#include <tdf/mesh/triangle_mesh.h>

#include <string>

namespace tdf {

/// The material written beside an OBJ. Map names are written as given, so pass paths relative
/// to the OBJ's folder (usually bare file names of PNGs written next to it).
struct ObjMaterial {
    std::string name = "material";
    std::string albedo_map;  ///< `map_Kd`; empty = none
    std::string normal_map;  ///< tangent-space normal map (OpenGL, green up); empty = none
};

/// Writes `obj_path` and, beside it, `<stem>.mtl` (always: it carries the material name even
/// without maps). Vertices are `v x y z [r g b]` (colours when the mesh has them), UVs `vt u v`
/// in OBJ convention (v up, as TriangleMesh stores them), faces `f v/vt` (or `f v` without
/// UVs); normals are not written since every reader, ours included, recomputes them (spec 1.2).
/// The normal map is named twice, as `norm` and as `map_Bump -bm 1`, so that Blender's importer
/// and other readers find it (spec 12.1).
void write_obj(const std::string& obj_path, const TriangleMesh& mesh, const ObjMaterial& material = {});

/// Writes a binary glTF 2.0 file: one mesh, one primitive (TRIANGLES), one material with
/// `baseColorTexture` (when `albedo` is given) and `normalTexture` (when `normal_map` is given),
/// both embedded as 8-bit PNG (rounded). Attributes: POSITION, NORMAL, TANGENT (xyz + w
/// handedness, glTF convention: bitangent = cross(normal, tangent) * w) and TEXCOORD_0 when
/// the mesh has UVs, COLOR_0 when it has vertex colours. glTF's texture v points down, so
/// TEXCOORD_0 = (u, 1 - v). Vertices are split per distinct (position, uv, tangent) corner
/// because glTF has a single index buffer. Null images are simply left out.
void write_glb(const std::string& path, const TriangleMesh& mesh, const Image* albedo = nullptr,
               const Image* normal_map = nullptr);

}  // namespace tdf
