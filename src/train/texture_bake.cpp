#include <tdf/train/texture_bake.h>

#include <tdf/atlas/gutter.h>
#include <tdf/core/parallel.h>

namespace tdf {

BakedMaps bake_field(const TextureField& field, const TriangleMesh& mesh, int size, int gutter) {
    BakedMaps maps;
    maps.raster = rasterize_uv(mesh, size);
    // Texels a chart only partly covers get true surface values, not dilated ones: at seams
    // bilinear and mip lookups read them (spec 12.5).
    add_partial_texels(mesh, maps.raster);
    const UvRaster& raster = maps.raster;
    std::vector<Vec3f> points;
    std::vector<std::size_t> texels;
    points.reserve(raster.covered_count());
    texels.reserve(raster.covered_count());
    for (std::size_t t = 0; t < raster.texel_count(); ++t) {
        const int f = raster.triangle[t];
        if (f < 0) continue;
        const Vec3i& tri = mesh.triangles[std::size_t(f)];
        const Vec3f w = raster.barycentric[t];
        points.push_back(mesh.positions[std::size_t(tri.x)] * w.x + mesh.positions[std::size_t(tri.y)] * w.y +
                         mesh.positions[std::size_t(tri.z)] * w.z);
        texels.push_back(t);
    }
    std::vector<FieldOutputs> outputs(points.size());
    field.evaluate(points.data(), points.size(), outputs.data());

    maps.albedo = Image(size, size, 3, 0.5f);
    maps.tactile_normal = Image(size, size, 3, 0.0f);
    for (std::size_t t = 0; t < raster.texel_count(); ++t) maps.tactile_normal.data()[3 * t + 2] = 1.0f;
    parallel_for(points.size(), 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t t = texels[k];
            std::copy(&outputs[k].albedo.x, &outputs[k].albedo.x + 3, maps.albedo.data() + 3 * t);
            std::copy(&outputs[k].normal.x, &outputs[k].normal.x + 3, maps.tactile_normal.data() + 3 * t);
        }
    });
    dilate_gutter(maps.albedo, raster.triangle, gutter);
    dilate_gutter(maps.tactile_normal, raster.triangle, gutter);
    return maps;
}

Image encode_normal_map(const Image& normals) {
    Image out(normals.width(), normals.height(), 3);
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        const float* n = normals.data() + 3 * p;
        const Vec3f u = normalize_or_zero({n[0], n[1], n[2]});
        for (int c = 0; c < 3; ++c) out.data()[3 * p + std::size_t(c)] = (u[c] + 1.0f) * 0.5f;
    }
    return out;
}

}  // namespace tdf
