#include <tdf/scene/camera.h>

#include <tdf/core/error.h>

#include <cmath>

namespace tdf {

Mat4f Mat4f::identity() {
    Mat4f r;
    for (int i = 0; i < 4; ++i) r.m[i][i] = 1.f;
    return r;
}

Vec4f Mat4f::operator*(Vec4f v) const {
    Vec4f r;
    for (int i = 0; i < 4; ++i) r[i] = m[i][0] * v.x + m[i][1] * v.y + m[i][2] * v.z + m[i][3] * v.w;
    return r;
}

Mat4f Mat4f::operator*(const Mat4f& b) const {
    Mat4f r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            for (int k = 0; k < 4; ++k) r.m[i][j] += m[i][k] * b.m[k][j];
    return r;
}

Camera Camera::orbit(float elevation_deg, float azimuth_deg, float radius, float fovy_deg, int width,
                     int height, Vec3f target) {
    const float e = radians(elevation_deg), a = radians(azimuth_deg);
    const Vec3f offset{radius * std::cos(e) * std::sin(a), -radius * std::sin(e),
                       radius * std::cos(e) * std::cos(a)};
    Camera camera = look_at(target + offset, target, Kind::Perspective, width, height);
    camera.fovy_degrees = fovy_deg;
    return camera;
}

Camera Camera::look_at(Vec3f position, Vec3f target, Kind kind, int width, int height) {
    Camera camera;
    camera.kind = kind;
    camera.width = width;
    camera.height = height;
    camera.position = position;
    camera.back = safe_normalize(position - target);
    Vec3f up_world{0, 1, 0};
    Vec3f right = cross(up_world, camera.back);
    if (length_squared(right) < 1e-12f) {
        // Degenerate in the reference (spec 13.16): take the limit as back tilts toward +Z.
        up_world = Vec3f{0, 0, camera.back.y > 0 ? -1.f : 1.f};
        right = cross(up_world, camera.back);
    }
    camera.right = safe_normalize(right);
    camera.up = safe_normalize(cross(camera.back, camera.right));
    return camera;
}

Camera Camera::tactile_patch(Vec3f surface_point, Vec3f unit_normal, int width, int height, float distance,
                             float half_extent) {
    Camera camera = look_at(surface_point + unit_normal * distance, surface_point, Kind::Orthographic,
                            width, height);
    camera.half_extent = half_extent;
    return camera;
}

float Camera::tan_half_fovy() const { return std::tan(radians(fovy_degrees) * 0.5f); }

namespace {
// Image-plane scale per unit NDC: camera-space offset at z = -1 (perspective) or world offset
// (orthographic) for NDC x = 1 and NDC y = 1.
void ndc_scale(const Camera& c, float& sx, float& sy) {
    const float half_h = c.kind == Camera::Kind::Perspective ? c.tan_half_fovy() : c.half_extent;
    sx = half_h * c.aspect();
    // NDC y grows down the image (row 0 = NDC -1, spec 2.2); camera y grows up unless flipped.
    sy = c.flip_rows ? half_h : -half_h;
}
}  // namespace

Ray Camera::generate_ray(float px, float py) const {
    float sx, sy;
    ndc_scale(*this, sx, sy);
    const float ndc_x = 2.f * px / float(width) - 1.f;
    const float ndc_y = 2.f * py / float(height) - 1.f;
    Ray ray;
    ray.tnear = near_plane;
    ray.tfar = far_plane;
    if (kind == Kind::Perspective) {
        ray.origin = position;
        ray.direction = right * (ndc_x * sx) + up * (ndc_y * sy) - back;
    } else {
        ray.origin = position + right * (ndc_x * sx) + up * (ndc_y * sy);
        ray.direction = -back;
    }
    return ray;
}

void Camera::ray_derivatives(Vec3f& dorigin_dpx, Vec3f& dorigin_dpy, Vec3f& ddir_dpx, Vec3f& ddir_dpy) const {
    float sx, sy;
    ndc_scale(*this, sx, sy);
    const Vec3f dx = right * (2.f * sx / float(width));
    const Vec3f dy = up * (2.f * sy / float(height));
    if (kind == Kind::Perspective) {
        dorigin_dpx = dorigin_dpy = Vec3f{};
        ddir_dpx = dx;
        ddir_dpy = dy;
    } else {
        dorigin_dpx = dx;
        dorigin_dpy = dy;
        ddir_dpx = ddir_dpy = Vec3f{};
    }
}

Vec3f Camera::world_to_camera_direction(Vec3f d) const { return {dot(right, d), dot(up, d), dot(back, d)}; }

Vec3f Camera::camera_to_world_direction(Vec3f d) const { return right * d.x + up * d.y + back * d.z; }

Vec3f Camera::world_to_camera_point(Vec3f p) const { return world_to_camera_direction(p - position); }

Mat4f Camera::pose_matrix() const {
    Mat4f r = Mat4f::identity();
    for (int i = 0; i < 3; ++i) {
        r.m[i][0] = right[i];
        r.m[i][1] = up[i];
        r.m[i][2] = back[i];
        r.m[i][3] = position[i];
    }
    return r;
}

Mat4f Camera::view_matrix() const {
    // inverse([R, c]) = [R^T, -R^T c] for orthonormal R.
    Mat4f r = Mat4f::identity();
    const Vec3f axes[3] = {right, up, back};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) r.m[i][j] = axes[i][j];
        r.m[i][3] = -dot(axes[i], position);
    }
    return r;
}

Mat4f Camera::projection_matrix() const {
    Mat4f p;
    const float n = near_plane, f = far_plane;
    const float y_sign = flip_rows ? 1.f : -1.f;
    if (kind == Kind::Perspective) {
        const float t = tan_half_fovy();
        p.m[0][0] = 1.f / (t * aspect());
        p.m[1][1] = y_sign / t;
        p.m[2][2] = -(f + n) / (f - n);
        p.m[2][3] = -2.f * f * n / (f - n);
        p.m[3][2] = -1.f;
    } else {
        p.m[0][0] = 1.f / (half_extent * aspect());
        p.m[1][1] = y_sign / half_extent;
        p.m[2][2] = -2.f / (f - n);
        p.m[2][3] = -(f + n) / (f - n);
        p.m[3][3] = 1.f;
    }
    return p;
}

}  // namespace tdf
