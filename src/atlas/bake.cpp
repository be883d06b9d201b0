#include <tdf/atlas/bake.h>
#include <tdf/atlas/gutter.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

namespace tdf {

Image bake_vertex_colors(const TriangleMesh& mesh, int size) {
    if (!mesh.has_colors()) throw_error("{}: the mesh has no vertex colours to bake", mesh.source_path);
    UvRaster raster = rasterize_uv(mesh, size);
    add_partial_texels(mesh, raster);
    Image image = interpolate_vertex_attribute(mesh, raster, mesh.colors);
    dilate_gutter(image, raster.triangle, 0);
    return image;
}

Image rebake_texture(const TriangleMesh& source, const Image& texture, const TriangleMesh& target, int size) {
    if (texture.empty()) throw_error("{}: no texture to re-bake", source.source_path);
    if (!source.has_uvs())
        throw_error("{}: the source mesh has no UVs to read the texture through", source.source_path);
    if (source.triangles.size() != target.triangles.size())
        throw_error("{}: cannot re-bake onto a mesh with different faces ({} vs {})",
                    source.source_path,
                    source.triangles.size(),
                    target.triangles.size());
    for (std::size_t f = 0; f < source.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k)
            if (source.triangles[f][k] != target.triangles[f][k])
                throw_error(
                    "{}: cannot re-bake: face {} differs between the meshes", source.source_path, f + 1);
    UvRaster raster = rasterize_uv(target, size);
    add_partial_texels(target, raster);
    Image image(size, size, texture.channels());
    parallel_for(raster.texel_count(), 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) {
            const int f = raster.triangle[t];
            if (f < 0) continue;
            const Vec3i& old = source.uv_triangles[std::size_t(f)];
            const Vec3f w = raster.barycentric[t];
            const Vec2f uv = source.uvs[std::size_t(old.x)] * w.x + source.uvs[std::size_t(old.y)] * w.y +
                             source.uvs[std::size_t(old.z)] * w.z;
            sample_bilinear(texture, uv, image.data() + t * std::size_t(texture.channels()));
        }
    });
    dilate_gutter(image, raster.triangle, 0);
    return image;
}

}  // namespace tdf
