#include <tdf/render/gbuffer.h>

#include <algorithm>

namespace tdf {

void GBuffer::resize(int new_width, int new_height) {
    width = new_width;
    height = new_height;
    const std::size_t n = pixel_count();
    mask.resize(n);
    triangle.resize(n);
    barycentric.resize(n);
    position.resize(n);
    depth.resize(n);
    normal.resize(n);
    tangent.resize(n);
    handedness.resize(n);
    uv.resize(n);
    duv_dx.resize(n);
    duv_dy.resize(n);
}

void GBuffer::clear_pixel(std::size_t i) {
    mask[i] = 0.f;
    triangle[i] = -1;
    barycentric[i] = {};
    position[i] = {};
    depth[i] = 0.f;
    normal[i] = {};
    tangent[i] = {};
    handedness[i] = 0.f;
    uv[i] = {};
    duv_dx[i] = {};
    duv_dy[i] = {};
}

void GBuffer::copy_tile(const GBuffer& tile, int x0, int y0) {
    for (int y = 0; y < tile.height; ++y) {
        const std::size_t s = tile.index(0, y), d = index(x0, y0 + y), n = std::size_t(tile.width);
        std::copy_n(tile.mask.begin() + long(s), n, mask.begin() + long(d));
        std::copy_n(tile.triangle.begin() + long(s), n, triangle.begin() + long(d));
        std::copy_n(tile.barycentric.begin() + long(s), n, barycentric.begin() + long(d));
        std::copy_n(tile.position.begin() + long(s), n, position.begin() + long(d));
        std::copy_n(tile.depth.begin() + long(s), n, depth.begin() + long(d));
        std::copy_n(tile.normal.begin() + long(s), n, normal.begin() + long(d));
        std::copy_n(tile.tangent.begin() + long(s), n, tangent.begin() + long(d));
        std::copy_n(tile.handedness.begin() + long(s), n, handedness.begin() + long(d));
        std::copy_n(tile.uv.begin() + long(s), n, uv.begin() + long(d));
        std::copy_n(tile.duv_dx.begin() + long(s), n, duv_dx.begin() + long(d));
        std::copy_n(tile.duv_dy.begin() + long(s), n, duv_dy.begin() + long(d));
    }
}

}  // namespace tdf
