// All of tdf's CGAL use is in this translation unit (compile time, see the header).
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/ARAP_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>
#include <tdf/atlas/chart_parameterization.h>

#include <cmath>
#include <exception>

namespace tdf {

namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using VertexIndex = SurfaceMesh::Vertex_index;
namespace SMP = CGAL::Surface_mesh_parameterization;
}  // namespace

bool flatten_chart(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& triangles, bool arap,
                   std::vector<Vec2f>& uvs) {
    try {
        SurfaceMesh mesh;
        std::vector<VertexIndex> vertices;
        vertices.reserve(positions.size());
        for (const Vec3f& p : positions) vertices.push_back(mesh.add_vertex(Kernel::Point_3(p.x, p.y, p.z)));
        for (const Vec3i& t : triangles) {
            const auto face = mesh.add_face(
                vertices[std::size_t(t.x)], vertices[std::size_t(t.y)], vertices[std::size_t(t.z)]);
            if (face == SurfaceMesh::null_face()) return false;  // non-manifold or inconsistent
        }
        const auto border = CGAL::Polygon_mesh_processing::longest_border(mesh).first;
        if (border == SurfaceMesh::null_halfedge()) return false;  // closed: not a disk
        auto uv_map = mesh.add_property_map<VertexIndex, Kernel::Point_2>("v:uv").first;
        // Copies the solution out; false when it is not finite.
        const auto extract = [&]() {
            uvs.resize(positions.size());
            for (std::size_t i = 0; i < vertices.size(); ++i) {
                const Kernel::Point_2 uv = uv_map[vertices[i]];
                if (!std::isfinite(uv.x()) || !std::isfinite(uv.y())) return false;
                uvs[i] = Vec2f(float(uv.x()), float(uv.y()));
            }
            return true;
        };
        if (arap) {
            // ARAP cannot handle some tiny charts (two triangles with every vertex on the border
            // divide by zero: a CGAL precondition, unchecked in release builds, so look at the
            // result); LSCM then gives the answer.
            using Arap = SMP::ARAP_parameterizer_3<SurfaceMesh>;
            try {
                const SMP::Error_code status =
                    SMP::parameterize(mesh,
                                      Arap(Arap::Border_parameterizer(), Arap::Solver_traits(), 1000.0, 30),
                                      border,
                                      uv_map);
                if (status == SMP::OK && extract()) return true;
            } catch (const std::exception&) {
                // fall through to LSCM
            }
        }
        const SMP::Error_code status =
            SMP::parameterize(mesh, SMP::LSCM_parameterizer_3<SurfaceMesh>(), border, uv_map);
        return status == SMP::OK && extract();
    } catch (const std::exception&) {
        // CGAL reports precondition failures (e.g. a border it cannot handle) by throwing.
        return false;
    }
}

}  // namespace tdf
