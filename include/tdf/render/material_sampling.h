#pragma once
/// Per-pixel lookups of a SurfaceMaterial at a traced surface point: what the renderer draws and
/// what the optimizer uses as its targets (the base albedo and the tactile map, spec 3.1 step 5).
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/gbuffer.h>
#include <tdf/render/renderer.h>

namespace tdf {

/// A texel's first three channels as RGB, or grey for 1-2 channel textures; channel k at
/// texel[k * stride] (stride > 1: a texel of lookups written in planes).
inline Vec3f texel_rgb(const MipTexture& texture, const float* texel, std::size_t stride = 1) {
    return texture.channels() >= 3 ? Vec3f{texel[0], texel[stride], texel[2 * stride]}
                                   : Vec3f{texel[0], texel[0], texel[0]};
}

/// The mesh's vertex colour interpolated on `triangle` at barycentrics b = (b1, b2).
inline Vec3f vertex_color_at(const TriangleMesh& mesh, int triangle, Vec2f b) {
    const Vec3i& t = mesh.triangles[std::size_t(triangle)];
    return mesh.colors[std::size_t(t.x)] * (1.f - b.x - b.y) + mesh.colors[std::size_t(t.y)] * b.x +
           mesh.colors[std::size_t(t.z)] * b.y;
}
/// The same at pixel `i` of `g` (a hit).
inline Vec3f vertex_color_at(const TriangleMesh& mesh, const GBuffer& g, std::size_t i) {
    return vertex_color_at(mesh, g.triangle[i], g.barycentric[i]);
}

/// Albedo of pixel `i` (a hit) from the material's source: texture (trilinear over the whole
/// pyramid when `mipmapped`, else bilinear), vertex colours (barycentric) or the constant.
Vec3f sample_albedo(const SurfaceMaterial& material, const TriangleMesh& mesh, const GBuffer& g, std::size_t i,
                    bool mipmapped);

/// Tangent-space tactile normal of pixel `i` (a hit), laid by material.tactile_layout, trilinear
/// with LOD from the ray differentials, capped at `max_level` (-1 = whole pyramid); (0,0,1)
/// without a map. Not renormalised: callers that match the training renderer apply
/// safe_normalize (spec 3.1 step 5).
Vec3f sample_tactile(const SurfaceMaterial& material, const GBuffer& g, std::size_t i, int max_level = -1);

/// sqrt(3-D area / UV area): the mean surface length of one UV unit. Throws tdf::Error when the
/// mesh has no UV area.
double mesh_units_per_uv_unit(const TriangleMesh& mesh);

/// The UV scale that lays a tactile map at its physical size (tactile_layout.mode = physical): the
/// atlas's mean surface size per UV unit, mesh_units_per_uv_unit x mm_per_unit, divided by the
/// map's width in millimetres. Throws tdf::Error when the mesh has no UV area.
float physical_tactile_uv_scale(const TriangleMesh& mesh, float mm_per_unit, int map_width_pixels,
                                float mm_per_pixel);

}  // namespace tdf
