#pragma once
/// The per-pixel tangent frame and the TBN composition of a tangent-space normal (spec 3.3),
/// shared by the renderer and by the optimizer's gradients so both compute the same normal.
#include <tdf/core/vec.h>

namespace tdf {

/// Unit tangent T (dP/du), unit normal N and the chart's handedness w = +1 or -1 (tdf keeps the
/// sign the reference discards, spec 13.17; TangentMode::Reference gives w = +1 everywhere).
struct TangentFrame {
    Vec3f tangent;
    Vec3f normal;
    float handedness = 1.0f;
};

/// The frame's bitangent w normalize(N x T). With w = +1 it is the reference's -B for
/// B = normalize(T x N): its maps follow the OpenGL "green up" convention (spec 3.3).
inline Vec3f frame_bitangent(const TangentFrame& f) {
    return safe_normalize(cross(f.normal, f.tangent)) * f.handedness;
}

/// T px + w normalize(N x T) py + N pz, before normalisation: the reference's
/// T px - B py + N pz (spec 3.3) with our handedness. safe_normalize of it is the shading normal;
/// the visualizer's viewspace_normal uses it unnormalised (spec 3.9 / 13.19).
inline Vec3f tbn_product(const TangentFrame& f, Vec3f p) {
    return f.tangent * p.x + frame_bitangent(f) * p.y + f.normal * p.z;
}

/// The transpose: the components of a world vector `v` along T, w normalize(N x T) and N (for an
/// orthonormal frame, the tangent-space vector whose tbn_product is `v`).
inline Vec3f tbn_transpose_product(const TangentFrame& f, Vec3f v) {
    return {dot(f.tangent, v), dot(frame_bitangent(f), v), dot(f.normal, v)};
}

}  // namespace tdf
