#pragma once
/// Statistics of tangent-space normals that say how much relief a surface has, independent of
/// where the relief is: used to tell whether learned normals look like the touched exemplar
/// (issue 6) without a pixel-to-pixel correspondence.
#include <tdf/core/image.h>
#include <tdf/core/vec.h>

#include <cstddef>
#include <vector>

namespace tdf {

/// Histogram of the normals' tilt from +z (the height gradient's steepness), normalised to sum
/// 1: `bins` equal bins over [0, max_degrees] degrees, tilts beyond it counted in the last bin.
/// Invariant to in-plane rotation and to the position of the relief; zero vectors are skipped.
/// Returns all zeros when no normal counts.
struct TiltHistogramOptions {
    int bins = 16;
    float max_degrees = 60.0f;
};
std::vector<double> tilt_histogram(const Vec3f* normals, std::size_t count, const TiltHistogramOptions& options = {});
/// The same over the first three channels of every pixel of `normals` (3+ channels).
std::vector<double> tilt_histogram(const Image& normals, const TiltHistogramOptions& options = {});

/// L1 distance between two histograms of the same length (0 = equal, 2 = disjoint).
double histogram_l1_distance(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace tdf
