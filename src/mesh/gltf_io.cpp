// Placeholder until the glTF loader lands.
#include <tdf/mesh/mesh_io.h>

#include <tdf/core/error.h>

namespace tdf {

TriangleMesh load_gltf(const std::string& path, const MeshLoadOptions&) {
    throw_error("'{}': glTF input is not implemented yet", path);
}

}  // namespace tdf
