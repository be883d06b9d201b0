// Placeholder until the PLY loader lands.
#include <tdf/mesh/mesh_io.h>

#include <tdf/core/error.h>

namespace tdf {

TriangleMesh load_ply(const std::string& path, const MeshLoadOptions&) {
    throw_error("'{}': PLY input is not implemented yet", path);
}

}  // namespace tdf
