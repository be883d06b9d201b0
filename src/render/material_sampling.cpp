#include <tdf/render/material_sampling.h>

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

Vec3f sample_tactile(const SurfaceMaterial& material, const GBuffer& g, std::size_t i, int max_level,
                     const TactileLayoutTransform& layout) {
    if (!material.tactile) return {0, 0, 1};
    float texel[kMaxTextureChannels];
    const float s = layout.uv_scale;
    material.tactile->sample_trilinear(g.uv[i] * s, g.duv_dx[i] * s, g.duv_dy[i] * s, texel, max_level);
    return {texel[0], texel[1], texel[2]};
}

}  // namespace tdf
