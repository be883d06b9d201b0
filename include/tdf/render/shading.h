#pragma once
/// The per-pixel shading library shared by `tdf render` and the optimizer, forward and backward
/// side by side: tangent-frame composition (spec 3.3), view-space rotation (spec 3.5), the two
/// lighting models (training spec 3.4, visualizer 3.9) and the lambertian colour. Backward
/// functions are vector-Jacobian products, finite-difference checked
/// (tests/unit/render_shading_grad_test.cpp). All inline: called per pixel.
#include <tdf/core/rng.h>
#include <tdf/core/tangent_frame.h>
#include <tdf/core/vec.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace tdf {

/// shading_normal() before its final normalisation (the visualizer's unnormalised
/// viewspace_normal, spec 3.9 / 13.19).
inline Vec3f shading_normal_unnormalized(Vec3f T, Vec3f N, float w, Vec3f p) {
    return tbn_product(TangentFrame{T, N, w}, p);
}

/// The training renderer's `magic3d` point-light sample (spec 3.4). Three draws in the
/// reference's order: azimuth phi ~ U[-pi, pi), elevation theta ~ U[pi/6, pi/2), distance
/// d ~ U[3, 5). Frame: z_l = normalize(camera_position), x_l = normalize((z_l.y, -z_l.x, 0)),
/// y_l = normalize(z_l x x_l); L = d (cos theta cos phi x_l + cos theta sin phi y_l + sin theta z_l).
/// When the camera lies on the world Z axis (elevation 0, azimuth 0 or 180) x_l is a zero vector
/// in the reference (spec 13.16); tdf uses x_l = (1, 0, 0) there. Any unit vector perpendicular
/// to z_l gives the same light distribution (phi is uniform), so only the roll of the sample
/// changes. Returns the world-space light position.
Vec3f sample_magic3d_light(Rng& rng, Vec3f camera_position);
/// The light of that frame at given angles (radians) and distance, without a draw: the sample
/// above is magic3d_light(camera_position, theta, phi, d) at its drawn values.
Vec3f magic3d_light(Vec3f camera_position, float theta, float phi, float distance);

/// The one diffuse shade of both renderers: ambient + (1 - ambient) max(0, n . l) for a unit
/// direction l toward the light. The visualizer's ambient is --ambient_light_ratio (0.1, spec
/// 3.9); the training renderer's 0.5 diffuse + 0.5 ambient colour is ambient 0.5 (spec 3.4).
inline float visualizer_shade(Vec3f n, Vec3f direction_to_light, float ambient) {
    return ambient + (1.f - ambient) * std::max(0.f, dot(n, direction_to_light));
}

/// Training shade (spec 3.4): 0.5 max(0, n . l) + 0.5 with l = normalize(light - p), the point
/// light's direction at p. Its normal is detached in training: no backward on purpose (see
/// lambertian_backward).
inline float training_shade(Vec3f n, Vec3f light_position, Vec3f p) {
    return visualizer_shade(n, safe_normalize(light_position - p), 0.5f);
}

/// Direction toward the light from orbit angles in degrees (spec 3.9, same formula as orbit
/// cameras): (cos e sin a, -sin e, cos e cos a).
Vec3f orbit_direction(float elevation_deg, float azimuth_deg);

/// How a surface colour and the light combine into the lambertian pass.
enum class ColorSpace {
    /// The reference (default, for parity with its renders): the stored values (8-bit texture
    /// levels / 255, vertex colours, the constant) times the shade, clamped to [0, 1].
    Raw,
    /// What glTF viewers and Blender do with `baseColorTexture`: the stored values are decoded
    /// from sRGB, multiplied by the shade in linear light, clamped, and encoded back to sRGB for
    /// display. Decoding follows filtering here (GPUs decode texels first); the two differ only
    /// where filtering mixes very different texels.
    Srgb,
};
/// "raw" or "srgb".
const char* color_space_name(ColorSpace space);
/// Parses "raw" / "srgb"; throws tdf::Error otherwise.
ColorSpace parse_color_space(const std::string& name);

/// The sRGB transfer functions (IEC 61966-2-1), for values in [0, 1].
inline float srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
inline float linear_to_srgb(float c) {
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

/// The displayed colour of a surface of stored colour `albedo` lit by `shade` (ambient + diffuse,
/// >= 0) under `space`; every channel in [0, 1].
inline Vec3f lit_color(Vec3f albedo, float shade, ColorSpace space) {
    Vec3f c;
    for (int k = 0; k < 3; ++k) {
        if (space == ColorSpace::Raw)
            c[k] = std::clamp(albedo[k] * shade, 0.f, 1.f);
        else
            c[k] =
                linear_to_srgb(std::clamp(srgb_to_linear(std::clamp(albedo[k], 0.f, 1.f)) * shade, 0.f, 1.f));
    }
    return c;
}

// ---- Differentiable steps of the optimizer (each with its backward) ----------------------
/// World shading normal from a tangent-space normal p (spec 3.3):
/// normalize(T px + w normalize(N x T) py + N pz). With w = +1 this is the reference's
/// normalize(T px - B py + N pz), B = normalize(T x N). w = -1 on mirrored UV charts flips the
/// bitangent so the map's green channel still points toward increasing v (tdf default; the
/// reference discards the sign, which TangentMode::Reference reproduces by giving w = +1).
/// safe_normalize (x / sqrt(max(|x|^2, 1e-20))), so a zero frame (background) gives zero.
inline Vec3f compose_shading_normal(const TangentFrame& f, Vec3f p) {
    return safe_normalize(tbn_product(f, p));
}

/// dL/dp from dL/dn_s for compose_shading_normal (the frame is a constant).
inline Vec3f compose_shading_normal_backward(const TangentFrame& f, Vec3f p, Vec3f d_shading_normal) {
    const Vec3f d_raw = normalize_backward(tbn_product(f, p), d_shading_normal, 1e-10f);
    return tbn_transpose_product(f, d_raw);
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

/// Lambertian colour albedo * shade.
inline Vec3f lambertian(Vec3f albedo, float shade) { return albedo * shade; }

/// dL/d(albedo) for lambertian. Matches reference: the shading normal is detached inside the
/// shade, so image losses on the lambertian never reach the normal (spec 3.4); there is no
/// normal backward on purpose.
inline Vec3f lambertian_backward(float shade, Vec3f d_colour) { return d_colour * shade; }

}  // namespace tdf
