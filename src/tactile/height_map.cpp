#include <tdf/tactile/height_map.h>

#include <tdf/core/error.h>

#include <cmath>
#include <cstdlib>

namespace tdf {

ImageMetadata height_map_metadata(const HeightMap& map) {
    ImageMetadata metadata;
    metadata[kMetaMmPerPixel] = map.mm_per_pixel > 0 ? fmt::format("{}", map.mm_per_pixel) : kUnknown;
    if (map.reference_scale_mm > 0) metadata[kMetaReferenceScale] = fmt::format("{}", map.reference_scale_mm);
    if (map.reference_mm_per_pixel > 0)
        metadata[kMetaReferencePixel] = fmt::format("{}", map.reference_mm_per_pixel);
    if (!map.source.empty()) metadata[kMetaSource] = map.source;
    if (map.pixel_heights) metadata[kMetaHeightUnit] = "pixel";
    if (map.tileable) metadata[kMetaTileable] = "1";
    return metadata;
}

float metadata_float(const ImageMetadata& metadata, const char* key, const std::string& path) {
    const auto it = metadata.find(key);
    if (it == metadata.end() || it->second == kUnknown) return 0.0f;
    char* end = nullptr;
    const float value = std::strtof(it->second.c_str(), &end);
    if (end == it->second.c_str() || *end != '\0' || !std::isfinite(value) || value < 0)
        throw_error("{}: metadata '{}' = '{}' is not a non-negative number", path, key, it->second);
    return value;
}

void apply_height_metadata(const ImageMetadata& metadata, HeightMap& map) {
    const auto unit = metadata.find(kMetaHeightUnit);
    map.pixel_heights = unit != metadata.end() && unit->second == "pixel";
    const auto tileable = metadata.find(kMetaTileable);
    map.tileable = tileable != metadata.end() && tileable->second == "1";
}

void write_height_map(const std::string& path, const HeightMap& map) {
    TDF_CHECK_EQ(map.height.channels(), 1);
    write_exr(path, map.height, height_map_metadata(map), ExrPixelType::Float);
}

HeightMap read_height_map(const std::string& path) {
    ImageMetadata metadata;
    HeightMap map;
    map.height = read_image(path, metadata);
    if (map.height.channels() != 1)
        throw_error("{}: expected a 1-channel height map, got {} channels", path, map.height.channels());
    if (!map.height.all_finite()) throw_error("{}: the height map contains NaN or infinite values", path);
    map.mm_per_pixel = metadata_float(metadata, kMetaMmPerPixel, path);
    map.reference_scale_mm = metadata_float(metadata, kMetaReferenceScale, path);
    map.reference_mm_per_pixel = metadata_float(metadata, kMetaReferencePixel, path);
    apply_height_metadata(metadata, map);
    map.source = path;
    return map;
}

}  // namespace tdf
