#include <tdf/core/error.h>
#include <tdf/render/shading.h>

#include <cmath>

namespace tdf {

Vec3f sample_magic3d_light(Rng& rng, Vec3f camera_position) {
    const float phi = rng.uniform(-kPi, kPi);
    const float theta = rng.uniform(kPi / 6.f, kPi / 2.f);
    const float distance = rng.uniform(3.f, 5.f);
    return magic3d_light(camera_position, theta, phi, distance);
}

Vec3f magic3d_light(Vec3f camera_position, float theta, float phi, float distance) {
    const Vec3f z = safe_normalize(camera_position);
    Vec3f x{z.y, -z.x, 0.f};
    x = length_squared(x) < 1e-12f ? Vec3f{1.f, 0.f, 0.f} : safe_normalize(x);
    const Vec3f y = safe_normalize(cross(z, x));
    const float ct = std::cos(theta);
    return (x * (ct * std::cos(phi)) + y * (ct * std::sin(phi)) + z * std::sin(theta)) * distance;
}

Vec3f orbit_direction(float elevation_deg, float azimuth_deg) {
    const float e = radians(elevation_deg), a = radians(azimuth_deg);
    return {std::cos(e) * std::sin(a), -std::sin(e), std::cos(e) * std::cos(a)};
}

const char* color_space_name(ColorSpace space) { return space == ColorSpace::Raw ? "raw" : "srgb"; }

ColorSpace parse_color_space(const std::string& name) {
    if (name == "raw") return ColorSpace::Raw;
    if (name == "srgb") return ColorSpace::Srgb;
    throw_error("unknown color space '{}' (valid: raw, srgb)", name);
}

}  // namespace tdf
