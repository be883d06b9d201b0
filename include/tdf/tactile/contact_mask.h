#pragma once
/// Where the sensor actually touched the object: the reference's contact mask and square crop
/// (spec 6.2 steps 4-5).
#include <tdf/core/image.h>

#include <string>

namespace tdf {

struct ContactRegion {
    /// 1 channel, 1 inside the filled convex hull of the largest contact component, else 0.
    Image mask;
    /// The square crop in pixels: columns [x, x + side), rows [y, y + side).
    int x = 0, y = 0, side = 0;
};

/// Matches reference (spec 6.2 step 4-5): pixels with height > `depth_threshold` (mm), dilated
/// once with a 5x5 square, the largest 8-connected component (by pixel count; the reference
/// ranks OpenCV contours by polygon area), its convex hull filled, that hull's bounding box made
/// square by trimming the longer side symmetrically, then the reference's centre crop, which
/// drops the last row and column of an odd side. Throws tdf::Error naming `what` when no pixel
/// exceeds the threshold or the crop is smaller than 2 pixels.
ContactRegion find_contact_region(const Image& height, float depth_threshold, const std::string& what);

}  // namespace tdf
