#include <tdf/train/texel_atlas.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/release.h>

#include <algorithm>

namespace tdf {

TexelAtlas TexelAtlas::build(const TriangleMesh& mesh, int size) {
    if (!mesh.has_uvs()) throw_error("{}: the texture-space optimizer needs UVs", mesh.source_path);
    TexelAtlas atlas;
    atlas.size = size;
    atlas.raster = rasterize_uv(mesh, size);
    // Texels a chart only partly covers hold true surface values (seams, tiny charts), not copies.
    add_partial_texels(mesh, atlas.raster);
    const UvRaster& r = atlas.raster;
    atlas.source.assign(r.texel_count(), -1);
    for (std::size_t t = 0; t < r.texel_count(); ++t) {
        const int f = r.triangle[t];
        if (f < 0) continue;
        const Vec3i& tri = mesh.triangles[std::size_t(f)];
        const Vec3i& uvt = mesh.uv_triangles[std::size_t(f)];
        const Vec3f w = r.barycentric[t];
        atlas.source[t] = int(atlas.texels.size());
        atlas.texels.push_back(std::uint32_t(t));
        atlas.points.push_back(mesh.positions[std::size_t(tri.x)] * w.x + mesh.positions[std::size_t(tri.y)] * w.y +
                               mesh.positions[std::size_t(tri.z)] * w.z);
        atlas.uvs.push_back(mesh.uvs[std::size_t(uvt.x)] * w.x + mesh.uvs[std::size_t(uvt.y)] * w.y +
                            mesh.uvs[std::size_t(uvt.z)] * w.z);
    }
    if (atlas.texels.empty())
        throw_error("{}: no texel of the {}x{} atlas is covered by a UV triangle", mesh.source_path, size, size);

    // Gutter sources ring by ring (8-neighbourhood, as dilate_gutter): an empty texel next to the
    // filled region copies the filled neighbour that comes first in a fixed order, edge
    // neighbours before diagonal ones, so the result does not depend on threads or visit order.
    static constexpr int kOffsets[8][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
    std::vector<int> frontier;
    std::vector<std::uint8_t> queued(r.texel_count(), 0);
    const auto push_empty_neighbours = [&](int x, int y) {
        for (const auto& o : kOffsets) {
            const int nx = x + o[0], ny = y + o[1];
            if (nx < 0 || ny < 0 || nx >= size || ny >= size) continue;
            const std::size_t n = std::size_t(ny) * std::size_t(size) + std::size_t(nx);
            if (atlas.source[n] >= 0 || queued[n]) continue;
            queued[n] = 1;
            frontier.push_back(int(n));
        }
    };
    for (std::uint32_t t : atlas.texels) push_empty_neighbours(int(t) % size, int(t) / size);
    std::sort(frontier.begin(), frontier.end());
    std::vector<int> next, picked;
    while (!frontier.empty()) {
        picked.assign(frontier.size(), -1);
        for (std::size_t k = 0; k < frontier.size(); ++k) {
            const int x = frontier[k] % size, y = frontier[k] / size;
            for (const auto& o : kOffsets) {
                const int nx = x + o[0], ny = y + o[1];
                if (nx < 0 || ny < 0 || nx >= size || ny >= size) continue;
                const int s = atlas.source[std::size_t(ny) * std::size_t(size) + std::size_t(nx)];
                if (s >= 0) {
                    picked[k] = s;
                    break;
                }
            }
        }
        for (std::size_t k = 0; k < frontier.size(); ++k) atlas.source[std::size_t(frontier[k])] = picked[k];
        frontier.swap(next);
        frontier.clear();
        for (int t : next) push_empty_neighbours(t % size, t / size);
        std::sort(frontier.begin(), frontier.end());
    }
    return atlas;
}

void TexelAtlas::release_target_inputs() {
    release(raster.barycentric);
    release(uvs);
}

void TexelAtlas::fill_gutter(Image& map) const {
    TDF_CHECK(map.width() == size && map.height() == size);
    const std::size_t c = std::size_t(map.channels());
    float* data = map.data();
    parallel_for(texel_count(), 1 << 14, [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) {
            const int s = source[t];
            if (s < 0) continue;
            const std::size_t from = texels[std::size_t(s)];
            if (from == t) continue;
            std::copy_n(data + from * c, c, data + t * c);
        }
    });
}

void TexelAtlas::fold_gutter_gradient(Image& gradient) const {
    TDF_CHECK(gradient.width() == size && gradient.height() == size);
    const std::size_t c = std::size_t(gradient.channels());
    float* data = gradient.data();
    for (std::size_t t = 0; t < texel_count(); ++t) {
        const int s = source[t];
        const std::size_t to = s < 0 ? t : texels[std::size_t(s)];
        if (to == t) continue;
        for (std::size_t k = 0; k < c; ++k) {
            data[to * c + k] += data[t * c + k];
            data[t * c + k] = 0.0f;
        }
    }
}

namespace {
// The derivatives of UV per texel step of a size x size map: a one-texel footprint.
constexpr Vec2f texel_step_x(int size, float scale) { return {scale / float(size), 0.0f}; }
constexpr Vec2f texel_step_y(int size, float scale) { return {0.0f, -scale / float(size)}; }
}  // namespace

Image albedo_target(const TexelAtlas& atlas, const SurfaceMaterial& material, const TriangleMesh& mesh) {
    TDF_CHECK(atlas.has_target_inputs());
    Image map(atlas.size, atlas.size, 3, 0.5f);
    using Source = SurfaceMaterial::AlbedoSource;
    parallel_for(atlas.covered_count(), 4096, [&](std::size_t begin, std::size_t end) {
        float texel[kMaxTextureChannels];
        for (std::size_t k = begin; k < end; ++k) {
            Vec3f c = material.albedo_constant;
            if (material.albedo_source == Source::Texture) {
                material.albedo->sample_trilinear(atlas.uvs[k], texel_step_x(atlas.size, 1.0f),
                                                  texel_step_y(atlas.size, 1.0f), texel, -1);
                c = texel_rgb(*material.albedo, texel);
            } else if (material.albedo_source == Source::VertexColors) {
                const std::size_t t = atlas.texels[k];
                const Vec3i& tri = mesh.triangles[std::size_t(atlas.raster.triangle[t])];
                const Vec3f w = atlas.raster.barycentric[t];
                c = mesh.colors[std::size_t(tri.x)] * w.x + mesh.colors[std::size_t(tri.y)] * w.y +
                    mesh.colors[std::size_t(tri.z)] * w.z;
            }
            std::copy(&c.x, &c.x + 3, map.data() + 3 * std::size_t(atlas.texels[k]));
        }
    });
    atlas.fill_gutter(map);
    return map;
}

Vec3f sample_tactile_layout(const SurfaceMaterial& material, Vec2f uv, Vec2f duv_dx, Vec2f duv_dy) {
    if (!material.tactile) return {0, 0, 1};
    const float s = material.tactile_layout.uv_scale;
    float texel[kMaxTextureChannels];
    material.tactile->sample_trilinear(uv * s, duv_dx * s, duv_dy * s, texel, -1);
    return safe_normalize(Vec3f{texel[0], texel[1], texel[2]});
}

Image tactile_target(const TexelAtlas& atlas, const SurfaceMaterial& material) {
    TDF_CHECK(atlas.has_target_inputs());
    Image map(atlas.size, atlas.size, 3, 0.0f);
    for (std::size_t t = 0; t < map.pixel_count(); ++t) map.data()[3 * t + 2] = 1.0f;
    if (material.tactile) {
        parallel_for(atlas.covered_count(), 4096, [&](std::size_t begin, std::size_t end) {
            for (std::size_t k = begin; k < end; ++k) {
                const Vec3f n = sample_tactile_layout(material, atlas.uvs[k], texel_step_x(atlas.size, 1.0f),
                                                      texel_step_y(atlas.size, 1.0f));
                std::copy(&n.x, &n.x + 3, map.data() + 3 * std::size_t(atlas.texels[k]));
            }
        });
    }
    atlas.fill_gutter(map);
    return map;
}

}  // namespace tdf
