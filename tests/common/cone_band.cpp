#include "common/cone_band.h"

#include <cmath>

namespace tdf::test {

TriangleMesh make_cone_band(int segments, float u_step, float v_step, float height, float top_radius,
                            bool turned_first, Vec2f turned_at) {
    constexpr float kTurn = 6.28318531f;
    TriangleMesh mesh;
    mesh.source_path = "cone band";
    for (int ring = 0; ring < 2; ++ring)
        for (int s = 0; s < segments; ++s) {
            const float phi = kTurn * float(s) / float(segments);
            const float r = ring == 0 ? 1.0f : top_radius;
            mesh.positions.push_back({r * std::sin(phi), height * float(ring), r * std::cos(phi)});
        }
    for (int ring = 0; ring < 2; ++ring)
        for (int s = 0; s <= segments; ++s) mesh.uvs.push_back({u_step * float(s), v_step * float(ring)});
    const int turned = int(mesh.uvs.size());
    // Corners (0,0) (1,0) (1,1) (0,1) of the quad go to (1,0) (1,1) (0,1) (0,0) of the rectangle.
    for (Vec2f c : {Vec2f{u_step, 0}, Vec2f{u_step, v_step}, Vec2f{0, v_step}, Vec2f{0, 0}})
        mesh.uvs.push_back(turned_at + c);
    const auto p = [segments](int ring, int s) { return ring * segments + s % segments; };
    const auto t = [segments](int ring, int s) { return ring * (segments + 1) + s; };
    for (int s = 0; s < segments; ++s) {
        Vec3i t0{t(0, s), t(0, s + 1), t(1, s + 1)}, t1{t(0, s), t(1, s + 1), t(1, s)};
        if (s == 0 && turned_first) t0 = {turned, turned + 1, turned + 2}, t1 = {turned, turned + 2, turned + 3};
        // Counter-clockwise seen from outside (u grows with phi, v with y).
        mesh.triangles.push_back({p(0, s), p(0, s + 1), p(1, s + 1)});
        mesh.uv_triangles.push_back(t0);
        mesh.triangles.push_back({p(0, s), p(1, s + 1), p(1, s)});
        mesh.uv_triangles.push_back(t1);
    }
    compute_normals(mesh);
    compute_tangents(mesh);
    return mesh;
}

}  // namespace tdf::test
