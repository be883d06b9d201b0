#pragma once
// What the multi-part scene generators in tools/ share: face centroids (their ground truth is a
// rule on them) and the OBJ text with one `usemtl` per run of faces of one part.
#include <tdf/mesh/triangle_mesh.h>

#include <fmt/format.h>

#include <string>
#include <vector>

namespace tdf::tools {

inline Vec3f face_centroid(const TriangleMesh& mesh, std::size_t f) {
    const Vec3i& t = mesh.triangles[f];
    return (mesh.positions[std::size_t(t.x)] + mesh.positions[std::size_t(t.y)] + mesh.positions[std::size_t(t.z)]) *
           (1.f / 3.f);
}

/// `# <comment>`, `mtllib sphere.mtl`, `o <object>`, then positions, UVs and faces, with
/// `usemtl names[part[f]]` wherever the part changes.
inline std::string part_obj_text(const TriangleMesh& mesh, const std::vector<int>& part,
                                 const std::vector<std::string>& names, const std::string& comment,
                                 const std::string& object) {
    std::string text = fmt::format("# {}\nmtllib sphere.mtl\no {}\n", comment, object);
    for (const Vec3f& p : mesh.positions) text += fmt::format("v {:.6f} {:.6f} {:.6f}\n", p.x, p.y, p.z);
    for (const Vec2f& t : mesh.uvs) text += fmt::format("vt {:.6f} {:.6f}\n", t.x, t.y);
    int current = -1;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        if (part[f] != current) text += "usemtl " + names[std::size_t(current = part[f])] + "\n";
        const Vec3i& p = mesh.triangles[f];
        const Vec3i& t = mesh.uv_triangles[f];
        text += fmt::format("f {}/{} {}/{} {}/{}\n", p.x + 1, t.x + 1, p.y + 1, t.y + 1, p.z + 1, t.z + 1);
    }
    return text;
}

}  // namespace tdf::tools
