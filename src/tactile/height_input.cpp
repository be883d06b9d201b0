#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/height_input.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/npy_reader.h>
#include <tdf/tactile/poisson.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/tactile/tmd_reader.h>

#include <cmath>
#include <cstdlib>
#include <limits>

namespace tdf {

namespace {

// A 2-D numeric array as a 1-channel image; `name` for messages.
Image array_image(const NpyArray& array, const std::string& where) {
    if (array.shape.size() != 2 || array.shape[0] < 3 || array.shape[1] < 3)
        throw_error(
            "{}: expected a 2-D array of at least 3x3, got shape ({})", where, fmt::join(array.shape, ", "));
    if (array.dtype.size() < 2 || array.dtype[1] != 'f')
        throw_error("{}: expected a float array, got dtype '{}'", where, array.dtype);
    Image image(int(array.shape[1]), int(array.shape[0]), 1);
    for (std::size_t i = 0; i < array.values.size(); ++i) {
        if (!std::isfinite(array.values[i]))
            throw_error("{}: NaN or infinite value at row {}, column {}",
                        where,
                        i / array.shape[1],
                        i % array.shape[1]);
        // A float64 such as 1e300 would become +Inf as a 32-bit height (and NaN normals later).
        if (std::fabs(array.values[i]) > double(std::numeric_limits<float>::max()))
            throw_error("{}: value {} at row {}, column {} does not fit a 32-bit float",
                        where,
                        array.values[i],
                        i / array.shape[1],
                        i % array.shape[1]);
        image.data()[i] = float(array.values[i]);
    }
    return image;
}

const NpyArray& member(const std::map<std::string, NpyArray>& arrays, const std::string& name,
                       const std::string& path) {
    const auto it = arrays.find(name);
    if (it == arrays.end()) {
        std::string names;
        for (const auto& entry : arrays) names += (names.empty() ? "" : ", ") + entry.first;
        throw_error(
            "{}: no '{}' array (the archive holds: {})", path, name, names.empty() ? "nothing" : names);
    }
    return it->second;
}

HeightInput load_npz(const std::string& path, const HeightInputOptions& options) {
    const auto arrays = read_npz(path);
    HeightInput input;
    input.capture = true;
    CaptureSource source = options.source;
    if (source == CaptureSource::Auto)
        source = arrays.count("dm") ? CaptureSource::DepthMap : CaptureSource::Gradients;
    if (source == CaptureSource::DepthMap) {
        input.map.height = array_image(member(arrays, "dm", path), path + ": dm");
        input.kind = "npz dm";
    } else {
        const Image gx = array_image(member(arrays, "gx", path), path + ": gx");
        const Image gy = array_image(member(arrays, "gy", path), path + ": gy");
        input.map.height = integrate_gradients(gx, gy, path);
        input.kind = "npz gradients";
    }
    input.map.mm_per_pixel = kGelSightMiniMmPerPixel;  // .npz captures carry no scale
    return input;
}

bool is_grey(const Image& image) {
    if (image.channels() < 3) return true;
    for (std::size_t p = 0; p < image.pixel_count(); ++p) {
        const float* v = image.data() + p * std::size_t(image.channels());
        if (v[0] != v[1] || v[1] != v[2]) return false;
    }
    return true;
}

float metadata_number(const ImageMetadata& metadata, const char* key, const std::string& path) {
    const std::string& text = metadata.at(key);
    char* end = nullptr;
    const float value = std::strtof(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || !std::isfinite(value))
        throw_error("{}: metadata '{}' = '{}' is not a number", path, key, text);
    return value;
}

HeightInput load_image(const std::string& path, const HeightInputOptions& options) {
    ImageMetadata metadata;
    const Image image = read_image(path, metadata);
    if (!image.all_finite()) throw_error("{}: the image contains NaN or infinite values", path);
    HeightInput input;
    input.map.mm_per_pixel = metadata_float(metadata, kMetaMmPerPixel, path);
    input.map.reference_scale_mm = metadata_float(metadata, kMetaReferenceScale, path);
    input.map.reference_mm_per_pixel = metadata_float(metadata, kMetaReferencePixel, path);
    ImageKind kind = options.image_kind;
    if (kind == ImageKind::Auto) kind = is_grey(image) ? ImageKind::Height : ImageKind::Normal;
    const bool exr = lower_extension(path) == ".exr";
    if (kind == ImageKind::Height) {
        input.map.height = image.channels() == 1 ? image : image.channel_range(0, 1);
        if (metadata.count(kMetaHeightMin) && metadata.count(kMetaHeightMax)) {  // ours: restore mm
            const float lo = metadata_number(metadata, kMetaHeightMin, path);
            const float range = metadata_number(metadata, kMetaHeightMax, path) - lo;
            for (float& v : input.map.height.values()) v = lo + v * range;
        } else if (!exr) {
            for (float& v : input.map.height.values()) v *= options.image_height_mm;
        }
        apply_height_metadata(metadata, input.map);
        input.kind = "height image";
    } else {
        const TactileMap normals = decode_tactile_map(image, metadata, path);
        input.map.height = height_from_normals(normals.normals, 0.1f, path);
        input.kind = "normal map";
        input.from_normals = true;
        input.normals = normals.normals;
        // Integrated heights are in pixel widths; mm need the pixel size (set below).
        input.map.reference_scale_mm = 0;
        input.map.reference_mm_per_pixel = 0;
    }
    return input;
}

}  // namespace

HeightInput load_height_input(const std::string& path, const HeightInputOptions& options) {
    if (!std::isfinite(options.mm_per_pixel) || options.mm_per_pixel < 0)
        throw_error("{}: the pixel size (--mm-per-pixel) must be a finite number >= 0, got {}",
                    path,
                    options.mm_per_pixel);
    if (!std::isfinite(options.image_height_mm) || !(options.image_height_mm > 0))
        throw_error("{}: the full-scale height (--height-mm) must be a finite positive number, got {}",
                    path,
                    options.image_height_mm);
    const std::string ext = lower_extension(path);
    HeightInput input;
    if (ext == ".npz") {
        input = load_npz(path, options);
    } else if (ext == ".npy") {
        input.map.height = array_image(read_npy(path), path);
        input.kind = "npy";
        input.capture = true;
        input.map.mm_per_pixel = kGelSightMiniMmPerPixel;
    } else if (ext == ".tmd") {
        input.map = read_tmd(path).map;
        input.kind = "tmd";
    } else {
        input = load_image(path, options);
    }
    if (options.size_mm > 0) input.map.mm_per_pixel = options.size_mm / float(input.map.height.width());
    if (options.mm_per_pixel > 0) input.map.mm_per_pixel = options.mm_per_pixel;
    if (input.map.mm_per_pixel <= 0 && !input.map.pixel_heights)
        log_warning(
            "{}: physical size unknown (no sensor metadata); recorded as unknown: give --size-mm (width "
            "in mm) or --mm-per-pixel for a texture at its real size",
            path);
    if (input.from_normals) {
        if (input.map.mm_per_pixel > 0)
            for (float& v : input.map.height.values()) v *= input.map.mm_per_pixel;
        else
            input.map.pixel_heights = true;  // slopes stay true without a size
    }
    if (options.invert)
        for (float& v : input.map.height.values()) v = -v;
    input.map.source = path;
    return input;
}

}  // namespace tdf
