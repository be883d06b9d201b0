#include <tdf/render/gbuffer.h>

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

}  // namespace tdf
