#pragma once
/// The common currency of the tactile pipeline: a height field in millimetres together with the
/// lateral size of its pixels, so that textures keep their physical scale from sensor to mesh.
#include <tdf/core/image.h>
#include <tdf/io/image_io.h>

#include <string>

namespace tdf {

/// GelSight Mini: 21 x 25 mm over 240 x 320 pixels, about 85 micrometres per pixel (paper
/// section 3; spec 6.1). Used when a capture carries no scale of its own (.npz files).
constexpr float kGelSightMiniMmPerPixel = 0.085f;

/// Metadata keys written with tactile images (PNG tEXt chunks / EXR string attributes).
constexpr const char* kMetaMmPerPixel = "tdf:mm_per_pixel";            ///< lateral pixel size, mm
constexpr const char* kMetaReferenceScale = "tdf:reference_scale_mm";  ///< spec 6.2 step 6 `scale`
/// HeightMap::reference_mm_per_pixel: the capture's pixel size, which the reference amplitude counts per.
constexpr const char* kMetaReferencePixel = "tdf:reference_mm_per_pixel";
constexpr const char* kMetaSource = "tdf:source";                      ///< input file of the pipeline
/// Height range of a 16-bit PNG preview of a height map (mm): reading it back restores mm.
constexpr const char* kMetaHeightMin = "tdf:height_min_mm";
constexpr const char* kMetaHeightMax = "tdf:height_max_mm";
/// "pixel" when heights are in pixel widths (HeightMap::pixel_heights), else absent (mm).
constexpr const char* kMetaHeightUnit = "tdf:height_unit";
/// "1" for a map that wraps around (HeightMap::tileable).
constexpr const char* kMetaTileable = "tdf:tileable";
/// Written as the value of kMetaMmPerPixel when the pixel size is not known.
constexpr const char* kUnknown = "unknown";

struct HeightMap {
    Image height;            ///< 1 channel, millimetres, row 0 = top of the image, x right
    float mm_per_pixel = 0;  ///< lateral size of one (square) pixel in mm; 0 = unknown
    /// The reference's patch amplitude `scale` (height range of the contact crop, spec 6.2
    /// step 6); 0 when the map did not come from a step-1 patch. Selects the reference's
    /// normal amplitude (spec 6.4 step 3).
    float reference_scale_mm = 0;
    /// The pixel size (mm) of the capture that reference_scale_mm was measured on. The
    /// reference amplitude counts slopes per pixel of that capture, so that resampling the
    /// patch keeps them (a 158 px contact crop stretched to 256 px lost 38 % of its slopes,
    /// issue 28); 0 = per pixel of this map.
    float reference_mm_per_pixel = 0;
    std::string source;  ///< the file it came from, for messages
    /// Heights are in pixel widths, not mm: an integrated normal map whose pixel size is
    /// unknown. Its slopes are still true (physical amplitude uses a gain of 1).
    bool pixel_heights = false;
    /// 1 channel, the map's size: 1 where the texture lies that synthesis may copy (contact
    /// region of a capture, textured region of an image); empty = everywhere.
    Image texture_mask;
    /// The map wraps around (a tileable quilt): normals use periodic differences.
    bool tileable = false;
};

/// The metadata of `map` (keys above; zero values are left out, except an unknown pixel size,
/// written as "unknown").
ImageMetadata height_map_metadata(const HeightMap& map);

/// Reads a float metadata value; 0 when `key` is absent or "unknown". Throws tdf::Error naming `path` when
/// the value is not a finite non-negative number.
float metadata_float(const ImageMetadata& metadata, const char* key, const std::string& path);

/// Sets `pixel_heights` and `tileable` of `map` from kMetaHeightUnit / kMetaTileable.
void apply_height_metadata(const ImageMetadata& metadata, HeightMap& map);

/// Writes a 1-channel float EXR in millimetres with the metadata above.
void write_height_map(const std::string& path, const HeightMap& map);

/// Reads a height map written by write_height_map (or any 1-channel EXR in mm), restoring its
/// metadata. Throws tdf::Error naming the file when it is not a 1-channel finite EXR.
HeightMap read_height_map(const std::string& path);

}  // namespace tdf
