#pragma once
/// Does touching the finished asset feel like the captured surface (issue 24)? The relief a
/// (virtual or real) GelSight measured, summarised by numbers that do not depend on where the
/// pad landed, and the round trip's three ratios against the input capture.
#include <tdf/core/config.h>
#include <tdf/core/image.h>

#include <vector>

namespace tdf {

/// `height` (1 channel) minus its least-squares quadratic surface: the pressed object's form
/// (a sphere's cap, a cylinder's bend) taken out, as a GelSight pipeline takes out the shape.
Image remove_quadratic(const Image& height);

/// The detail of a height map in mm at `mm_per_pixel`, over `mask` (1 channel, empty = all):
/// its quadratic form removed, then what the high-pass of material_statistics.h keeps
/// (Gaussian sigma kDetailSigmaPx), so the pressed object's curvature does not count.
struct ReliefMeasure {
    double detail_tilt = 0;     ///< mean detail tilt of its normals, degrees
    double height_rms_mm = 0;   ///< RMS of the height minus its Gaussian low-pass, mm
    /// MaterialStatistics::scale_energy: the detail slope energy per octave band (sum 1), the
    /// relief's coarse spectrum at the pixel pitch.
    std::vector<double> scale_energy;
};
ReliefMeasure measure_relief(const Image& height_mm, float mm_per_pixel, const Image& mask = Image());

/// Which part of a capture a touch is compared with:
/// - `Whole`: every pixel. What an asset carries when the map is its scene's tactile map (the
///   optimizer lays the whole map over the atlas, flat stretches and all), so the round trip's
///   comparison: a sparse relief (dimples on a flat) is compared with the same share of flat.
/// - `Contact`: the textured region (texture_region of its detail tilt), the contact region of a
///   raw GelSight capture whose borders the sensor never touched.
enum class CaptureArea { Whole, Contact };

/// The input capture as a tactile normal map (decoded, 3+ channels) at `mm_per_pixel`: its
/// heights (integrate_normal_map, mirrored) measured over `area`. With `window` > 0 and smaller
/// than the capture: the mean over window x window crops on a grid (for Contact, those at least
/// half in the region, measured over it), so that a capture compares with touches of a smaller
/// pad as the pad would have measured it (the form removal and the 12 px high-pass take more
/// from a small window).
ReliefMeasure measure_capture(const Image& normals, float mm_per_pixel, int window = 0,
                              CaptureArea area = CaptureArea::Whole);

/// Simulated touches against the capture: the ratios of their mean detail tilt and mean height
/// RMS to the capture's, and spectrum_distance = half the L1 distance of the mean scale energy
/// from the capture's (0 = the same spectrum, 1 = disjoint).
struct TouchRoundTrip {
    double tilt_ratio = 0, height_rms_ratio = 0, spectrum_distance = 0;
    ReliefMeasure capture, touches;  ///< touches: the means over the simulated touches
    Json to_json() const;
};
TouchRoundTrip compare_touches(const ReliefMeasure& capture, const std::vector<ReliefMeasure>& touches);

/// The round trip's aim: tilt and RMS ratios within [0.85, 1.15].
constexpr double kRoundTripMinRatio = 0.85, kRoundTripMaxRatio = 1.15;

}  // namespace tdf
