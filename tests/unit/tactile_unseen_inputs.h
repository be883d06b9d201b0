#pragma once
// Two kinds of tactile input that the shared samples do not cover (issue 28), synthesised in
// code so their provenance is this file: a gentle wood-veneer-like normal map (mean detail tilt
// under 1 degree, mostly flat) and a GelSight capture of a knitted glove (fine periodic loops
// on a contact region of about a third of the frame, flat gel around it). Used by the tactile
// tests and by tools/make_tactile_unseen_inputs.cpp, which writes them as files for the
// measurement script and the CLI.
#include <tdf/core/image.h>
#include <tdf/core/rng.h>
#include <tdf/tactile/normal_map.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>

namespace tdf::test {

/// Decoded tangent-space normals (OpenGL: +x right, +y up) of a photographed wood veneer's
/// kind of relief: fine grain lines running along x (48 sinusoids, wavelengths 4-16 px, each
/// within 34 degrees of across the grain), their depth varying in growth bands, with a few
/// smooth bands of nearly no relief. Written as an 8-bit PNG (1024 px) it measures a mean detail
/// tilt of 0.74 degrees over its textured region (79 % of the map), 73 % of it under 1 degree.
inline Image gentle_veneer_normals(int size = 1024, std::uint64_t seed = 2028) {
    constexpr float kTwoPi = 6.2831853f;
    Rng rng(seed);
    Image height(size, size, 1);  // in pixel widths
    for (int wave = 0; wave < 48; ++wave) {
        const float wavelength = rng.uniform(4.0f, 16.0f);
        const float angle = rng.uniform(-0.6f, 0.6f);  // across the grain, give or take 34 degrees
        const float fx = std::sin(angle) / wavelength, fy = std::cos(angle) / wavelength;
        const float phase = rng.uniform(0.0f, kTwoPi);
        // Equal slope amplitude per wave: height ~ wavelength.
        const float amplitude = 0.0036f * wavelength / kTwoPi;
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                height.at(x, y, 0) += amplitude * std::sin(kTwoPi * (fx * float(x) + fy * float(y)) + phase);
    }
    // Growth bands: the grain's depth varies slowly across it; about a tenth of the rows are
    // smooth bands (late wood polished flat).
    const float band_phase = rng.uniform(0.0f, kTwoPi);
    for (int y = 0; y < size; ++y) {
        const float s = std::sin(kTwoPi * float(y) / 173.0f + band_phase);
        const float depth = s < -0.95f ? 0.08f : 0.85f + 0.15f * s;
        for (int x = 0; x < size; ++x) height.at(x, y, 0) *= depth;
    }
    return normals_from_height(height, 1.0f);
}

/// A GelSight Mini capture (height in mm, 240 rows x 320 columns, 0.085 mm per pixel) of a
/// knitted glove pressed on the gel: rows of interlocking V-shaped loops (each loop two slanted
/// legs, a loop every `period` px across and 0.8 `period` down, alternate rows shifted by half a
/// loop), 0.1 mm deep, on a flat-topped elliptic press 0.9 mm deep whose contact region (above
/// 0.5 mm) covers 34 % of the frame; elsewhere flat gel with 2 micrometres of sensor noise.
inline Image knit_capture_heights(float period = 10.0f, std::uint64_t seed = 2028) {
    constexpr int kWidth = 320, kHeight = 240;
    Rng rng(seed);
    Image height(kWidth, kHeight, 1);
    const float cx = 168.0f, cy = 116.0f, ax = 112.0f, ay = 86.0f;  // the press's ellipse, px
    const float row_step = 0.8f * period;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const float dx = (float(x) - cx) / ax, dy = (float(y) - cy) / ay;
            const float r = std::sqrt(dx * dx + dy * dy);
            // Flat top to r = 0.8, smooth shoulder to 1.
            const float t = std::clamp((1.0f - r) / 0.2f, 0.0f, 1.0f);
            const float press = 0.9f * t * t * (3.0f - 2.0f * t);
            // The loop under (x, y): its row, and the position inside the loop.
            const float fy = float(y) / row_step;
            const int row = int(std::floor(fy));
            const float shift = (row % 2) != 0 ? 0.5f * period : 0.0f;
            const float u = std::fmod(float(x) + shift, period) / period - 0.5f;  // -0.5..0.5 across
            const float v = fy - float(row) - 0.5f;                               // -0.5..0.5 down
            // Two legs, each an elongated ridge slanted +-35 degrees from vertical.
            float loop = 0;
            for (float side : {-1.0f, 1.0f}) {
                const float lu = u - side * 0.22f, lv = v * 0.8f;
                const float c = std::cos(0.61f), s = side * std::sin(0.61f);
                const float across = (lu * c - lv * s) / 0.22f, along = (lu * s + lv * c) / 0.55f;
                const float q = 1.0f - across * across - along * along;
                loop = std::max(loop, q > 0 ? std::sqrt(q) : 0.0f);
            }
            height.at(x, y, 0) = press * (1.0f + 0.11f * loop) + 0.002f * rng.normal();
        }
    return height;
}

/// Writes a 1-channel image as a little-endian float64 .npy (what numpy.save writes), which
/// `tdf tactile` reads as a capture.
inline void write_npy_f8(const std::string& path, const Image& image) {
    std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" + std::to_string(image.height()) +
                         ", " + std::to_string(image.width()) + "), }";
    while ((10 + header.size() + 1) % 64 != 0) header += ' ';
    header += '\n';
    std::ofstream out(path, std::ios::binary);
    out.write("\x93NUMPY\x01\x00", 8);
    const char length[2] = {char(header.size() & 0xff), char(header.size() >> 8)};
    out.write(length, 2);
    out << header;
    for (float v : image.values()) {
        const double d = v;
        out.write(reinterpret_cast<const char*>(&d), sizeof d);
    }
}

}  // namespace tdf::test
