#pragma once
/// The differentiable per-pixel steps between the texture field and the losses, each with its
/// backward (vector-Jacobian product): TBN composition (spec 3.3), view-space rotation (spec
/// 3.5) and the training renderer's Lambert shade (spec 3.4). All inline: the trainer calls
/// them per pixel.
#include <tdf/core/tangent_frame.h>
#include <tdf/core/vec.h>

#include <algorithm>
#include <cmath>

namespace tdf {

/// d normalize(x) / dx applied to an upstream gradient g, for x / max(|x|, min_length):
/// (g - n (n.g)) / |x| above the threshold, g / min_length below it (where the map is linear).
inline Vec3f normalize_backward(Vec3f x, Vec3f g, float min_length) {
    const float len = length(x);
    if (len <= min_length) return g / min_length;
    const Vec3f n = x / len;
    return (g - n * dot(n, g)) / len;
}

/// World shading normal n_s = normalize(tbn_product(f, p)) (spec 3.3, the
/// reference's safe_normalize: x / sqrt(max(|x|^2, 1e-20))).
inline Vec3f compose_shading_normal(const TangentFrame& f, Vec3f p) {
    return safe_normalize(tbn_product(f, p));
}

/// dL/dp from dL/dn_s for compose_shading_normal (the frame is a constant).
inline Vec3f compose_shading_normal_backward(const TangentFrame& f, Vec3f p, Vec3f d_shading_normal) {
    const Vec3f d_raw = normalize_backward(tbn_product(f, p), d_shading_normal, 1e-10f);
    return {dot(f.tangent, d_raw), dot(frame_bitangent(f), d_raw), dot(f.normal, d_raw)};
}

/// The camera's axes in world coordinates: right, up and backward (OpenGL camera space: x right,
/// y up, z toward the viewer), i.e. the rows of camera_from_world's rotation.
struct ViewRotation {
    Vec3f right;
    Vec3f up;
    Vec3f back;
};

/// Camera-space normal n_v = normalize(R^T n_s) (spec 3.5, torch F.normalize eps 1e-12).
inline Vec3f view_space_normal(const ViewRotation& r, Vec3f n_world) {
    return normalize_or_zero({dot(r.right, n_world), dot(r.up, n_world), dot(r.back, n_world)}, 1e-12f);
}

/// dL/dn_s from dL/dn_v for view_space_normal.
inline Vec3f view_space_normal_backward(const ViewRotation& r, Vec3f n_world, Vec3f d_view_normal) {
    const Vec3f v(dot(r.right, n_world), dot(r.up, n_world), dot(r.back, n_world));
    const Vec3f d = normalize_backward(v, d_view_normal, 1e-12f);
    return r.right * d.x + r.up * d.y + r.back * d.z;
}

/// Training-renderer shade s = 0.5 max(0, n.l) + 0.5 with l = normalize(light - p) (spec 3.4:
/// diffuse and ambient colour 0.5).
inline float lambert_shade(Vec3f shading_normal, Vec3f light_position, Vec3f position) {
    const Vec3f l = safe_normalize(light_position - position);
    return 0.5f * std::max(0.0f, dot(shading_normal, l)) + 0.5f;
}

/// Lambertian colour albedo * shade.
inline Vec3f lambertian(Vec3f albedo, float shade) { return albedo * shade; }

/// dL/d(albedo) for lambertian. Matches reference: the shading normal is detached inside the
/// shade, so image losses on the lambertian never reach the normal (spec 3.4); there is no
/// normal backward on purpose.
inline Vec3f lambertian_backward(float shade, Vec3f d_colour) { return d_colour * shade; }

}  // namespace tdf
