#pragma once
/// GelSight "Binary TrueMap Data File v2.0" (.tmd) height maps.
///
/// Layout (little-endian): a 32-byte header text ("Binary TrueMap Data File v2.0\r\n\0"), a
/// NUL-terminated comment, uint32 columns, uint32 rows, float32 length x and length y (mm, the
/// whole map), float32 offset x and offset y (mm), then rows x columns float32 heights in mm,
/// row-major with row 0 at the top.
#include <tdf/tactile/height_map.h>

#include <string>

namespace tdf {

struct TmdFile {
    HeightMap map;          ///< heights in mm; mm_per_pixel = length_x_mm / columns
    float length_x_mm = 0;  ///< physical width of the whole map
    float length_y_mm = 0;  ///< physical height of the whole map
    float offset_x_mm = 0;
    float offset_y_mm = 0;
    std::string comment;
};

/// Reads a .tmd file. Throws tdf::Error naming the file for a wrong header, a truncated
/// file, non-positive sizes or lengths, or non-finite heights.
TmdFile read_tmd(const std::string& path);

}  // namespace tdf
