#include <tdf/scene/procedural_mesh.h>

#include <tdf/core/error.h>

#include <cmath>

namespace tdf {

TriangleMesh make_quad(float half_size, TangentMode tangents) {
    TriangleMesh mesh;
    const float h = half_size;
    mesh.positions = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    mesh.uv_triangles = mesh.triangles;
    mesh.source_path = "procedural quad";
    compute_normals(mesh);
    compute_tangents(mesh, tangents);
    return mesh;
}

TriangleMesh make_uv_sphere(float radius, int segments, int rings, TangentMode tangents) {
    TDF_CHECK(segments >= 3 && rings >= 2 && radius > 0.f);
    TriangleMesh mesh;
    mesh.source_path = "procedural sphere";
    // Position vertices: south pole, (rings - 1) latitude rings of `segments`, north pole.
    // UV vertices: a (segments + 1) x (rings + 1) grid, so the seam column is duplicated.
    const int south = 0;
    auto ring_vertex = [&](int ring, int s) { return 1 + (ring - 1) * segments + (s % segments); };
    const int north = 1 + (rings - 1) * segments;
    mesh.positions.push_back({0, -radius, 0});
    for (int r = 1; r < rings; ++r) {
        const float theta = kPi * float(r) / float(rings);  // from the south pole
        for (int s = 0; s < segments; ++s) {
            // u = atan2(x, z) / 2pi + 0.5: azimuth phi = 2pi u - pi.
            const float phi = 2.f * kPi * float(s) / float(segments) - kPi;
            mesh.positions.push_back({radius * std::sin(theta) * std::sin(phi), -radius * std::cos(theta),
                                      radius * std::sin(theta) * std::cos(phi)});
        }
    }
    mesh.positions.push_back({0, radius, 0});
    auto uv_vertex = [&](int ring, int s) { return ring * (segments + 1) + s; };
    for (int r = 0; r <= rings; ++r)
        for (int s = 0; s <= segments; ++s)
            mesh.uvs.push_back({float(s) / float(segments), float(r) / float(rings)});
    auto add = [&](Vec3i p, Vec3i t) {
        mesh.triangles.push_back(p);
        mesh.uv_triangles.push_back(t);
    };
    for (int s = 0; s < segments; ++s) {
        // Counter-clockwise seen from outside: u grows to the right, v grows up.
        add({south, ring_vertex(1, s + 1), ring_vertex(1, s)}, {uv_vertex(0, s), uv_vertex(1, s + 1), uv_vertex(1, s)});
        for (int r = 1; r + 1 < rings; ++r) {
            const int a = ring_vertex(r, s), b = ring_vertex(r, s + 1);
            const int c = ring_vertex(r + 1, s + 1), d = ring_vertex(r + 1, s);
            const int ta = uv_vertex(r, s), tb = uv_vertex(r, s + 1);
            const int tc = uv_vertex(r + 1, s + 1), td = uv_vertex(r + 1, s);
            add({a, b, c}, {ta, tb, tc});
            add({a, c, d}, {ta, tc, td});
        }
        add({ring_vertex(rings - 1, s), ring_vertex(rings - 1, s + 1), north},
            {uv_vertex(rings - 1, s), uv_vertex(rings - 1, s + 1), uv_vertex(rings, s)});
    }
    compute_normals(mesh);
    compute_tangents(mesh, tangents);
    return mesh;
}

}  // namespace tdf
