#pragma once
/// The files a run leaves (spec 1.4, with the fixes users asked for, spec 12.1): the mesh as
/// OBJ + MTL that references BOTH maps, a glTF binary with baseColorTexture and normalTexture,
/// the maps as 8-bit PNG (the reference's truncating encoding) and float EXR, and turntable
/// renders of the result.
#include <tdf/field/texture_field.h>
#include <tdf/mesh/mesh_writer.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/renderer.h>
#include <tdf/scene/embree_scene.h>
#include <tdf/tactile/height_export.h>
#include <tdf/train/run_config.h>
#include <tdf/train/texture_bake.h>

#include <string>
#include <vector>

namespace tdf {

/// Bakes `field` over `mesh` (the coordinates it was trained in) and writes the result with
/// write_asset, writing `export_mesh` (same faces and UVs, in the input's own coordinates,
/// SceneAssets::export_mesh) as the mesh when given, else `mesh`. Returns the baked maps for
/// further use (turntables).
BakedMaps export_asset(const std::string& folder, const std::string& name, const std::string& postfix,
                       const TextureField& field, const TriangleMesh& mesh, const RunConfig& config,
                       const TriangleMesh* export_mesh = nullptr);

/// Writes maps that are already made (baked from a field, or a texture-space optimizer's learned
/// maps) and the mesh: `<folder>/<name><postfix>{.obj,.mtl,.glb,_albedo.png,_tactile_normal.png,
/// _albedo.exr,_tactile_normal.exr}` (GLB and EXRs as `config` says). Every file is written
/// atomically; the GLB embeds the very bytes of the two PNG files. `mesh` is written as given:
/// pass it in the input's own coordinates (SceneAssets::export_mesh), with the UVs the maps were
/// made for. A multi-part run passes `parts`: one material per part in the MTL and the GLB (one
/// primitive per part), all on the same two maps (write_obj, write_glb).
///
/// With `height_scale` (mm_per_texel > 0) also the relief the exported normal map stands for
/// (issue 24): `_height.exr` (mm) and `_height.png` (16-bit), integrated from the normals as
/// the PNG decodes them and checked against them over the atlas's covered texels; the MTL
/// names it as `disp -mm base gain` (mesh units) and the GLB embeds it under the material's
/// `extras.tdf_height`. Returns the scale as exported_height_json (null without a height).
Json write_asset(const std::string& folder, const std::string& name, const std::string& postfix,
                 const BakedMaps& maps, const TriangleMesh& mesh, const RunConfig& config,
                 const FaceMaterials& parts = {}, const ExportScale* height_scale = nullptr);


/// Renders `views` azimuths of the exported asset (baked maps, visualizer shading, light from the
/// camera) and writes `<folder>/turntable/<pass>_<k>.png` for albedo, lambertian,
/// tactile_normal and shading_normal. Returns the files written.
/// `scene` must have been built from `mesh`.
std::vector<std::string> write_turntable(const std::string& folder, const TriangleMesh& mesh, const EmbreeScene& scene,
                                         const BakedMaps& maps, int views, int resolution);

/// The same renders of `mesh` with any material (e.g. the scene's input textures) into
/// `<folder>/<subfolder>/<pass>_<k>.png`.
std::vector<std::string> write_turntable(const std::string& folder, const std::string& subfolder,
                                         const TriangleMesh& mesh, const EmbreeScene& scene,
                                         const SurfaceMaterial& material, int views, int resolution);

/// The turntable's cameras: Camera::orbit(0, 360 k / views, radius, fovy_degrees, ..., target),
/// with the target at the bounding-box centre and the radius that fits the farthest vertex.
struct TurntableFraming {
    Vec3f target;
    float radius = 3.0f;
    float fovy_degrees = 50.0f;
};
TurntableFraming turntable_framing(const TriangleMesh& mesh);
/// The k-th of `views` turntable cameras (resolution x resolution) for that framing.
Camera turntable_camera(const TurntableFraming& framing, int k, int views, int resolution);

}  // namespace tdf
