#pragma once
/// Tangent-frame composition and the two lighting models (training spec 3.4, visualizer 3.9).
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

/// World shading normal from a tangent-space normal p (spec 3.3):
/// normalize(T px + w normalize(N x T) py + N pz). With w = +1 this is the reference's
/// normalize(T px - B py + N pz), B = normalize(T x N). w = -1 on mirrored UV charts flips the
/// bitangent so the map's green channel still points toward increasing v (tdf default; the
/// reference discards the sign, which TangentMode::Reference reproduces by giving w = +1).
/// Uses safe_normalize, so a zero frame (background) gives a zero vector. Inline: per pixel.
inline Vec3f shading_normal(Vec3f T, Vec3f N, float w, Vec3f tangent_space_normal) {
    return safe_normalize(shading_normal_unnormalized(T, N, w, tangent_space_normal));
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

/// Training shade (spec 3.4): 0.5 max(0, n . l) + 0.5 with l = normalize(light - p).
inline float training_shade(Vec3f n, Vec3f light_position, Vec3f p) {
    return 0.5f * std::max(0.f, dot(n, safe_normalize(light_position - p))) + 0.5f;
}

/// Visualizer shade (spec 3.9): ambient + (1 - ambient) max(0, n . l) for a unit direction
/// toward the light; ambient = --ambient_light_ratio (0.1).
inline float visualizer_shade(Vec3f n, Vec3f direction_to_light, float ambient) {
    return ambient + (1.f - ambient) * std::max(0.f, dot(n, direction_to_light));
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

}  // namespace tdf
