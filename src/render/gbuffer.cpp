#include <tdf/render/gbuffer.h>

namespace tdf {

void GBuffer::resize(int new_width, int new_height, GBufferFields new_fields) {
    width = new_width;
    height = new_height;
    fields = new_fields;
    const std::size_t n = pixel_count();
    const std::size_t ids = has_ids_and_depth() ? n : 0;
    mask.resize(n);
    triangle.resize(ids);
    barycentric.resize(ids);
    position.resize(n);
    depth.resize(ids);
    normal.resize(n);
    tangent.resize(n);
    handedness.resize(n);
    uv.resize(n);
    duv_dx.resize(n);
    duv_dy.resize(n);
}

void GBuffer::clear_pixel(std::size_t i) {
    mask[i] = 0.f;
    if (has_ids_and_depth()) {
        triangle[i] = -1;
        barycentric[i] = {};
        depth[i] = 0.f;
    }
    position[i] = {};
    normal[i] = {};
    tangent[i] = {};
    handedness[i] = 0.f;
    uv[i] = {};
    duv_dx[i] = {};
    duv_dy[i] = {};
}

}  // namespace tdf
