#pragma once
/// Seeded random views for training (spec 2.3 visual views, spec 2.4 tactile patch views).
/// The draws happen in the reference's order so a seeded run is reproducible.
#include <tdf/core/rng.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/scene/camera.h>

namespace tdf {

/// Visual (global) view distribution; the defaults are the reference's (spec 2.3).
struct VisualViewOptions {
    int min_elevation = -30;      ///< integer elevation in [min, max), degrees (numpy randint)
    int max_elevation = 30;
    int min_azimuth = -180;       ///< integer azimuth in [min, max), degrees
    int max_azimuth = 180;
    float radius = 1.25f;         ///< radius = radius + U[radius_range_min, radius_range_max)
    float radius_range_min = 0.f;
    float radius_range_max = 1.f;
    float fovy_degrees = 49.1f;
    int resolution = 512;         ///< output width = height
    bool random_ssaa = true;      ///< s = min(2, max(1, 2 U[0,1))); false: s = 1
    Vec3f target{};
};

/// One sampled visual view. `camera` has the INTERNAL resolution; results are resized back to
/// output_resolution x output_resolution (spec 3.8) when ssaa != 1.
struct VisualView {
    Camera camera;
    float ssaa = 1.f;
    int internal_width = 0;
    int internal_height = 0;
    int output_resolution = 0;
    float elevation_deg = 0;
    float azimuth_deg = 0;
    float radius = 0;
};

/// Internal resolution for an SSAA factor: ceil(resolution * s / 8) * 8, or `resolution` when
/// s == 1 (spec 2.3).
int ssaa_internal_resolution(int resolution, float ssaa);

/// Draws, in this order: elevation, azimuth, radius, SSAA factor (spec 2.3 / 9).
VisualView sample_visual_view(Rng& rng, const VisualViewOptions& options = {});

/// Tactile patch view (spec 2.4): a vertex chosen uniformly (one uniform_int draw over the
/// position vertices), camera at v + distance * n looking along -n, orthographic window of
/// 2 * half_extent, resolution x resolution, upright unless reference_flip is set (spec 13.13).
Camera sample_patch_view(Rng& rng, const TriangleMesh& mesh, int resolution = 512, float distance = 0.1f,
                         float half_extent = 0.075f, bool reference_flip = false);

}  // namespace tdf
