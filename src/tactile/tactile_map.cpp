#include <tdf/tactile/tactile_map.h>

#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/height_map.h>

namespace tdf {

TactileMap load_tactile_map(const std::string& path) {
    ImageMetadata metadata;
    const Image image = read_image(path, metadata);
    return decode_tactile_map(image, metadata, path);
}

TactileMap decode_tactile_map(const Image& image, const ImageMetadata& metadata, const std::string& path) {
    if (image.channels() < 3)
        throw_error(
            "{}: a {}-channel image is not a normal map (expected RGB or RGBA)", path, image.channels());
    if (!image.all_finite()) throw_error("{}: the normal map contains NaN or infinite values", path);
    TactileMap map;
    map.source = path;
    map.mm_per_pixel = metadata_float(metadata, kMetaMmPerPixel, path);
    map.normals = image.channels() == 3 ? image : image.channel_range(0, 3);
    bool grey = true, constant = true;
    const float* first = map.normals.pixel(0, 0);
    for (std::size_t p = 0; p < map.normals.pixel_count() && (grey || constant); ++p) {
        const float* v = map.normals.data() + 3 * p;
        grey = grey && v[0] == v[1] && v[1] == v[2];
        constant = constant && v[0] == first[0] && v[1] == first[1] && v[2] == first[2];
    }
    if (grey && !constant)
        throw_error(
            "{}: red, green and blue are equal everywhere: this looks like a grey height map, not a "
            "normal map (convert it with `tdf tactile convert`)",
            path);
    if (lower_extension(path) != ".exr")
        for (float& v : map.normals.values()) v = v * 2.0f - 1.0f;  // spec 1.3, not renormalised
    return map;
}

}  // namespace tdf
