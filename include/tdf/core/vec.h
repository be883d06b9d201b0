#pragma once
/// Small fixed-size vector types for hot loops (Eigen is used for solvers, not per pixel).
/// Conventions: world is right-handed, Y up, the object's front faces +Z (docs/conventions.md).
#include <algorithm>
#include <cmath>

namespace tdf {

struct Vec2f {
    float x = 0, y = 0;
    constexpr Vec2f() = default;
    constexpr Vec2f(float x_, float y_) : x(x_), y(y_) {}
    float& operator[](int i) { return (&x)[i]; }
    float operator[](int i) const { return (&x)[i]; }
};

struct Vec3f {
    float x = 0, y = 0, z = 0;
    constexpr Vec3f() = default;
    constexpr Vec3f(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    float& operator[](int i) { return (&x)[i]; }
    float operator[](int i) const { return (&x)[i]; }
};

struct Vec4f {
    float x = 0, y = 0, z = 0, w = 0;
    constexpr Vec4f() = default;
    constexpr Vec4f(float x_, float y_, float z_, float w_) : x(x_), y(y_), z(z_), w(w_) {}
    constexpr Vec4f(Vec3f v, float w_) : x(v.x), y(v.y), z(v.z), w(w_) {}
    Vec3f xyz() const { return {x, y, z}; }
    float& operator[](int i) { return (&x)[i]; }
    float operator[](int i) const { return (&x)[i]; }
};

struct Vec3i {
    int x = 0, y = 0, z = 0;
    constexpr Vec3i() = default;
    constexpr Vec3i(int x_, int y_, int z_) : x(x_), y(y_), z(z_) {}
    int& operator[](int i) { return (&x)[i]; }
    int operator[](int i) const { return (&x)[i]; }
};

inline Vec2f operator+(Vec2f a, Vec2f b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2f operator-(Vec2f a, Vec2f b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2f operator*(Vec2f a, float s) { return {a.x * s, a.y * s}; }
inline Vec2f operator*(float s, Vec2f a) { return a * s; }

inline Vec3f operator+(Vec3f a, Vec3f b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3f operator-(Vec3f a, Vec3f b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3f operator-(Vec3f a) { return {-a.x, -a.y, -a.z}; }
inline Vec3f operator*(Vec3f a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3f operator*(float s, Vec3f a) { return a * s; }
inline Vec3f operator*(Vec3f a, Vec3f b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline Vec3f operator/(Vec3f a, float s) { return a * (1.0f / s); }
inline Vec3f& operator+=(Vec3f& a, Vec3f b) { return a = a + b; }
inline Vec3f& operator-=(Vec3f& a, Vec3f b) { return a = a - b; }
inline Vec3f& operator*=(Vec3f& a, float s) { return a = a * s; }

inline float dot(Vec3f a, Vec3f b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3f cross(Vec3f a, Vec3f b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length_squared(Vec3f a) { return dot(a, a); }
inline float length(Vec3f a) { return std::sqrt(dot(a, a)); }
inline float dot(Vec2f a, Vec2f b) { return a.x * b.x + a.y * b.y; }
inline float length_squared(Vec2f a) { return dot(a, a); }
inline float length(Vec2f a) { return std::sqrt(dot(a, a)); }

/// The reference's `safe_normalize`: x / sqrt(max(|x|^2, 1e-20)) (spec notation section).
inline Vec3f safe_normalize(Vec3f a) { return a / std::sqrt(std::max(dot(a, a), 1e-20f)); }
/// torch `F.normalize`: x / max(|x|, eps); a zero vector stays zero.
inline Vec3f normalize_or_zero(Vec3f a, float eps = 1e-12f) {
    return a / std::max(length(a), eps);
}

/// d normalize(x) / dx applied to an upstream gradient g, for x / max(|x|, min_length):
/// (g - n (n.g)) / |x| above the threshold, g / min_length below it (where the map is linear).
inline Vec3f normalize_backward(Vec3f x, Vec3f g, float min_length) {
    const float len = length(x);
    if (len <= min_length) return g / min_length;
    const Vec3f n = x / len;
    return (g - n * dot(n, g)) / len;
}
inline bool is_finite(Vec3f a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline Vec3f min(Vec3f a, Vec3f b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3f max(Vec3f a, Vec3f b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

constexpr float kPi = 3.14159265358979323846f;
inline float radians(float degrees) { return degrees * (kPi / 180.0f); }
inline float degrees(float radians) { return radians * (180.0f / kPi); }

}  // namespace tdf
