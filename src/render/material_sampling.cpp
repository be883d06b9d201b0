#include <tdf/render/material_sampling.h>

#include <tdf/atlas/uv_metrics.h>
#include <tdf/core/error.h>

#include <cmath>

namespace tdf {

Vec3f sample_albedo(const SurfaceMaterial& material, const TriangleMesh& mesh, const GBuffer& g, std::size_t i,
                    bool mipmapped) {
    using Source = SurfaceMaterial::AlbedoSource;
    switch (material.albedo_source) {
        case Source::Texture: {
            float texel[kMaxTextureChannels];
            if (mipmapped)
                material.albedo->sample_trilinear(g.uv[i], g.duv_dx[i], g.duv_dy[i], texel, -1);
            else
                material.albedo->sample_bilinear(g.uv[i], texel);
            return texel_rgb(*material.albedo, texel);
        }
        case Source::VertexColors: return vertex_color_at(mesh, g, i);
        case Source::Constant: break;
    }
    return material.albedo_constant;
}

Vec3f sample_tactile(const SurfaceMaterial& material, const GBuffer& g, std::size_t i, int max_level) {
    if (!material.tactile) return {0, 0, 1};
    float texel[kMaxTextureChannels];
    const float s = material.tactile_layout.uv_scale;
    material.tactile->sample_trilinear(g.uv[i] * s, g.duv_dx[i] * s, g.duv_dy[i] * s, texel, max_level);
    return {texel[0], texel[1], texel[2]};
}

double mesh_units_per_uv_unit(const TriangleMesh& mesh) {
    double area_3d = 0, area_uv = 0;
    for (std::size_t f = 0; f < mesh.triangles.size() && mesh.has_uvs(); ++f) {
        const Vec3i& t = mesh.triangles[f];
        const Vec3i& u = mesh.uv_triangles[f];
        area_3d += triangle_area(mesh.positions[std::size_t(t.x)], mesh.positions[std::size_t(t.y)],
                                 mesh.positions[std::size_t(t.z)]);
        area_uv += 0.5 * std::fabs(signed_uv_area2(mesh.uvs[std::size_t(u.x)], mesh.uvs[std::size_t(u.y)],
                                                   mesh.uvs[std::size_t(u.z)]));
    }
    if (!(area_uv > 0) || !(area_3d > 0)) throw_error("{}: the UV atlas has no area", mesh.source_path);
    return std::sqrt(area_3d / area_uv);
}

float physical_tactile_uv_scale(const TriangleMesh& mesh, float mm_per_unit, int map_width_pixels,
                                float mm_per_pixel) {
    const double uv_mm = mesh_units_per_uv_unit(mesh) * double(mm_per_unit);
    return float(uv_mm / (double(map_width_pixels) * double(mm_per_pixel)));
}

}  // namespace tdf
