#pragma once
// The per-pixel arithmetic of the renderer's shading (shading normal, view-space normal, diffuse
// shade) over one tile at a time, in structure-of-arrays form so that the compiler vectorises it
// (16 lanes with AVX-512, 8 with AVX2, chosen at load time). Each lane computes exactly what the
// scalar functions of shading.h compute, in the same order, so every result is bit-identical.
#include <tdf/core/vec.h>
#include <tdf/render/gbuffer_lanes.h>
#include <tdf/render/shading.h>

namespace tdf {

// One tile's shading lanes, beside its G-buffer lanes (gbuffer_lanes.h: the frame and position
// each lane is shaded with): the texture lookups' results, and the outputs for the passes.
struct ShadeLanes {
    static constexpr int kMax = GBufferLanes::kMax;
    int count = 0;
    // Inputs, one plane a component (the texture lookups write them so): the sampled
    // tangent-space tactile normal p (not normalised), and the albedo, which shade_lanes does not
    // read (the caller's colour of each lane).
    alignas(64) float p[3][kMax];
    alignas(64) float albedo[3][kMax];
    // Outputs: the tactile normal as drawn (normalised in training), the shading normal, the
    // view-space normal and the diffuse shade.
    alignas(64) float tnx[kMax], tny[kMax], tnz[kMax];
    alignas(64) float snx[kMax], sny[kMax], snz[kMax];
    alignas(64) float vx[kMax], vy[kMax], vz[kMax];
    alignas(64) float shade[kMax];
    Vec3f albedo_at(int i) const { return {albedo[0][i], albedo[1][i], albedo[2][i]}; }
};

// What is constant over a frame.
struct ShadeConstants {
    bool training = true;        ///< renormalise p and the view-space normal (spec 3.1, 3.5)
    ViewRotation view;           ///< the camera's axes
    bool point_light = true;     ///< light_vector is a position (else a direction toward the light)
    Vec3f light_vector;
    float ambient = 0.5f;
};

// Computes the outputs of lanes [0, lanes.count), lane i shaded with g's lane i.
void shade_lanes(const GBufferLanes& g, ShadeLanes& lanes, const ShadeConstants& c);

}  // namespace tdf
