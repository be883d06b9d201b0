#include <tdf/mesh/mesh_io.h>

#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>

#include <filesystem>

namespace tdf {

TriangleMesh load_mesh(const std::string& path, const MeshLoadOptions& options) {
    if (!std::filesystem::exists(path)) throw_error("cannot open '{}': no such file", path);
    const std::string ext = lower_extension(path);
    if (ext == ".obj") return load_obj(path, options);
    if (ext == ".gltf" || ext == ".glb") return load_gltf(path, options);
    if (ext == ".ply") return load_ply(path, options);
    throw_error("'{}': unsupported mesh format '{}' (use .obj, .gltf, .glb or .ply)", path, ext);
}

void finish_loaded_mesh(TriangleMesh& mesh, const std::string& source, const MeshLoadOptions& options) {
    // A NaN texel would be baked, rendered and exported as 0 without a word.
    if (!mesh.albedo.empty() && !mesh.albedo.all_finite())
        throw_error("{}: the albedo texture '{}' contains NaN or infinite values",
                    source,
                    mesh.albedo_path.empty() ? std::string("(embedded)") : mesh.albedo_path);
    const std::size_t degenerate = validate_mesh(mesh, source);
    if (degenerate > 0)
        log_warning("{}: {} of {} faces have zero area (kept; they are never hit)", source, degenerate,
                    mesh.triangles.size());
    compute_normals(mesh);
    compute_tangents(mesh, options.tangent_mode);
}

}  // namespace tdf
