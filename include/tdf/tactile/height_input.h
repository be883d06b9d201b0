#pragma once
/// Every input a user may have, turned into a height map in millimetres (the pipeline's
/// `height` step): GelSight .npz captures (depth map or gradients), GelSight .tmd files, height
/// images (8/16-bit PNG, JPEG, EXR) and tangent-space normal-map images (integrated).
#include <tdf/tactile/height_map.h>

#include <string>

namespace tdf {

/// Which array of an .npz capture becomes the height map.
enum class CaptureSource {
    Auto,       ///< `dm` when present, else `gx`/`gy`
    DepthMap,   ///< `dm` (mm), as the reference does (spec 6.1)
    Gradients,  ///< Poisson integration of `gx`/`gy` (taken as mm per pixel), as the paper says
};

/// How an image file is interpreted.
enum class ImageKind {
    Auto,    ///< 1-2 channels or R = G = B: height; otherwise a normal map
    Height,  ///< values are heights (first channel)
    Normal,  ///< a tangent-space normal map (decoded as load_tactile_map does)
};

struct HeightInputOptions {
    CaptureSource source = CaptureSource::Auto;
    ImageKind image_kind = ImageKind::Auto;
    /// Lateral pixel size in mm; 0 = from `size_mm`, else from the file (.tmd header, tdf
    /// metadata; .npz/.npy captures: the GelSight Mini's 0.085 mm), else unknown (0, with one
    /// warning; never invented).
    float mm_per_pixel = 0;
    /// Physical width of the whole input in mm (0 = not given): mm_per_pixel = size_mm / width.
    float size_mm = 0;
    /// Height of a full-scale 8/16-bit height image (value 1.0) in mm; float EXR heights are
    /// taken as mm already.
    float image_height_mm = 1.0f;
    /// Negate heights (the reference's --invert_depth, spec 6.2 step 1).
    bool invert = false;
};

/// What was loaded, and whether it is a raw capture (then the contact mask applies).
struct HeightInput {
    HeightMap map;
    std::string kind;           ///< "npz dm", "npz gradients", "tmd", "height image", "normal map"
    bool capture = false;       ///< a raw GelSight capture with a contact region (.npz)
    bool from_normals = false;  ///< integrated from a normal-map image (heights in mm)
    Image normals;              ///< a normal-map image's decoded normals (else empty)
};

/// Loads `path` (kind chosen by extension: .npz, .npy, .tmd, else an image by content).
/// Integrated normal maps of unknown pixel size keep heights in pixel widths
/// (HeightMap::pixel_heights). A 16-bit PNG preview written by write_height_preview_png gets
/// its heights in mm back from its metadata.
/// Throws tdf::Error naming the file for missing arrays, wrong shapes or dtypes, NaNs,
/// and unreadable files.
HeightInput load_height_input(const std::string& path, const HeightInputOptions& options = {});

}  // namespace tdf
