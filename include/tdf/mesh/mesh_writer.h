#pragma once
/// Mesh files out: Wavefront OBJ + MTL, and binary glTF 2.0 (.glb) with embedded PNG maps.
/// Both are written atomically (temporary name, then rename) and throw tdf::Error naming the
/// file when they cannot be written.
#include <tdf/core/config.h>
#include <tdf/core/image.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/triangle_mesh.h>

#include <string>
#include <vector>

namespace tdf {

/// The material written beside an OBJ. Map names are written as given, so pass paths relative
/// to the OBJ's folder (usually bare file names of PNGs written next to it).
struct ObjMaterial {
    std::string name = "material";
    std::string albedo_map;  ///< `map_Kd`; empty = none
    std::string normal_map;  ///< tangent-space normal map (OpenGL, green up); empty = none
    /// Height map (16-bit grey PNG) written as `disp -mm base gain`: a texel of value t in
    /// [0, 1] lies base + gain x t mesh units above the surface (issue 24). Empty = none.
    std::string height_map;
    double height_base = 0, height_gain = 0;
};

/// One material per part of a multi-part asset (docs/multi-part-textures.md), every one using
/// the same maps: face f is in part `face_material[f]`, named `names[that]`. Empty = one
/// material for every face.
struct FaceMaterials {
    std::vector<std::string> names;
    std::vector<int> face_material;  ///< per face, index into names
    bool empty() const { return names.empty(); }
};

/// Writes `obj_path` and, beside it, `<stem>.mtl` (always: it carries the material name even
/// without maps). Vertices are `v x y z [r g b]` (colours when the mesh has them), UVs `vt u v`
/// in OBJ convention (v up, as TriangleMesh stores them), normals `vn` (one per vertex, the
/// mesh's `normals`: the renderer's area-weighted normals, so other programs shade the surface
/// tdf shades; tdf's own reader recomputes them, spec 1.2), faces `f v/vt/vn` (`f v//vn` without
/// UVs). The input's structure (TriangleMesh::face_groups) is kept as `o` / `g` lines, faces in
/// their order. The normal map is named twice, as `norm` and as `map_Bump -bm 1`, so that
/// Blender's importer and other readers find it (spec 12.1). With `parts`, the MTL holds one
/// material per part named as the part (each with `material`'s maps) and the faces switch with
/// `usemtl` where the part changes (faces keep their order).
void write_obj(const std::string& obj_path, const TriangleMesh& mesh, const ObjMaterial& material = {},
               const FaceMaterials& parts = {});

/// Maps for write_glb as PNG file bytes, embedded exactly as given (so an exporter can embed the
/// very bytes of the PNG files it writes beside the GLB). Empty = no map.
struct GlbMaps {
    std::string albedo_png;  ///< `baseColorTexture`: 8-bit, sRGB-encoded as glTF defines it
    std::string normal_png;  ///< `normalTexture`: tangent-space, OpenGL (green = +v), (n + 1) / 2
    /// The 16-bit height map (glTF core has no displacement): embedded as an image that no
    /// texture uses, named with its scale under the material's `extras.tdf_height` (`image` =
    /// its index, plus every key of `height_extras`). Empty = none.
    std::string height_png;
    Json height_extras = Json::object();
    /// `occlusionTexture` (8-bit grey: glTF reads its R channel): the relief's ambient occlusion.
    std::string occlusion_png;
};

/// The bytes of `image` as an 8-bit PNG file, from the same encoder (write_png) as PNG files.
std::string encode_png_bytes(const Image& image, Quantize quantize);

/// Writes a binary glTF 2.0 file with one material (metallic 0, roughness 1: as close to
/// Lambertian shading as glTF's PBR model gets): `baseColorTexture` and `normalTexture` when given.
/// Attributes: POSITION, NORMAL, TANGENT (xyz + w handedness, glTF convention: bitangent = cross(normal,
/// tangent) * w) and TEXCOORD_0 when the mesh has UVs, COLOR_0 when it has vertex colours and no albedo map
/// is given (glTF would multiply the two; tdf renders the texture alone). glTF's texture v points down, so
/// TEXCOORD_0 = (u, 1 - v). Vertices are split per distinct (position, uv, tangent) corner because glTF has a
/// single index buffer.
///
/// Structure: without TriangleMesh::face_groups, one node, one mesh, one primitive. With them,
/// the input's: for a glTF input one node per input node (its name and world matrix, flat under
/// the scene), each with its own mesh (the input mesh's name) and one primitive per input
/// primitive; positions, normals and tangents are written in the node's coordinates (the
/// loader's `world_from_node` un-applied, the winding restored under a mirroring matrix). For an
/// OBJ input one node per (`o`, `g`) pair and one primitive per `usemtl` material. Every
/// primitive uses the one material. With `parts`: one material per part (named as the part,
/// all sharing the two textures) and the primitives split further so each holds one part's
/// faces and uses its material. Throws tdf::Error for a singular node matrix.
void write_glb(const std::string& path, const TriangleMesh& mesh, const GlbMaps& maps,
               const FaceMaterials& parts = {});

/// write_glb with the maps encoded by encode_png_bytes (null or empty images are left out).
void write_glb(const std::string& path, const TriangleMesh& mesh, const Image* albedo = nullptr,
               const Image* normal_map = nullptr, Quantize quantize = Quantize::Round);

}  // namespace tdf
