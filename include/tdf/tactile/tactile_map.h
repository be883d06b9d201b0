#pragma once
/// Tactile normal maps as the optimizer consumes them (spec 1.3).
#include <tdf/core/image.h>
#include <tdf/io/image_io.h>

#include <string>

namespace tdf {

struct TactileMap {
    /// 3 channels: decoded tangent-space normals in [-1, 1], OpenGL convention (x = red = right,
    /// y = green = up, z = blue = out), NOT renormalised (spec 1.3: 127 decodes to -0.0039).
    Image normals;
    /// Lateral size of one texel in millimetres from the file's "tdf:mm_per_pixel" metadata;
    /// 0 when unknown (then the map covers the UV atlas once, like the reference).
    float mm_per_pixel = 0;
    std::string source;  ///< the file it was read from
};

/// Reads a tangent-space normal map: 8-bit or 16-bit PNG / JPEG decoded as v * 2 - 1 with v =
/// value / 255 (or / 65535), matching reference (spec 1.3); a float EXR holds decoded normals
/// as they are. A fourth (alpha) channel is dropped. Throws tdf::Error naming the file when it
/// has fewer than 3 channels, non-finite values, or equal R, G and B everywhere without being
/// constant (a grey height map, not a normal map). A constant map (flat) is accepted.
TactileMap load_tactile_map(const std::string& path);

/// load_tactile_map on an image already read from `path` (with read_image(path, metadata)).
TactileMap decode_tactile_map(const Image& image, const ImageMetadata& metadata, const std::string& path);

}  // namespace tdf
