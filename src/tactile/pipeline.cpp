#include <tdf/tactile/pipeline.h>

#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/contact_mask.h>
#include <tdf/tactile/high_pass.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/resample.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

std::pair<float, float> value_range(const Image& image) {
    const auto [lo, hi] = std::minmax_element(image.values().begin(), image.values().end());
    return {*lo, *hi};
}

}  // namespace

HeightMap extract_patch(const HeightInput& input, const PatchOptions& options, PatchSteps* steps) {
    const HeightMap& raw = input.map;
    const std::string& what = raw.source;
    HighPass high_pass = options.high_pass;
    float cutoff_mm = options.cutoff_mm;
    if (high_pass == HighPass::Auto) {
        high_pass = input.from_normals ? HighPass::Gaussian : HighPass::FftBlock;
        const int width = std::min(raw.height.width(), raw.height.height());
        cutoff_mm = 0.25f * float(width) * raw.mm_per_pixel;
    }
    const bool smooth =
        options.smooth == Toggle::On || (options.smooth == Toggle::Auto && !input.from_normals);
    const bool contact = options.contact == Toggle::On || (options.contact == Toggle::Auto && input.capture);
    Image filtered;
    switch (high_pass) {
        case HighPass::FftBlock:
            filtered = high_pass_fft_block(raw.height, options.freq_threshold);
            break;
        case HighPass::Gaussian:
            filtered = high_pass_gaussian(raw.height, cutoff_mm, raw.mm_per_pixel);
            break;
        case HighPass::Auto:  // resolved above
        case HighPass::None:
            filtered = raw.height;
            break;
    }
    Image smoothed =
        smooth
            ? bilateral_filter(filtered, options.bilateral_diameter, options.sigma_color, options.sigma_space)
            : filtered;
    int x = 0, y = 0, side = 0;
    Image mask;
    if (contact) {
        ContactRegion region = find_contact_region(raw.height, options.depth_threshold, what);
        x = region.x, y = region.y, side = region.side;
        mask = std::move(region.mask);
    } else {
        side = std::min(raw.height.width(), raw.height.height());
        x = (raw.height.width() - side) / 2;
        y = (raw.height.height() - side) / 2;
    }
    Image patch = crop(smoothed, x, y, side, side);
    // Matches reference: the amplitude `scale` is the crop's range before resampling (spec 6.2 step 6).
    const auto [lo, hi] = value_range(patch);
    if (!(hi - lo > 1e-6f))
        throw_error(
            "{}: the patch is flat (height range {} mm); nothing to turn into a texture", what, hi - lo);
    for (float& v : patch.values()) v -= lo;
    HeightMap out;
    out.source = raw.source;
    // Integrated normal maps already have true slopes: the reference's amplitude rule would
    // distort them, so they keep physical amplitude (normal_map_from_height, Amplitude::Auto).
    if (!input.from_normals) out.reference_scale_mm = hi - lo;
    out.mm_per_pixel = raw.mm_per_pixel;
    if (options.size > 0 && options.size != side) {
        patch = resize_lanczos(patch, options.size, options.size);
        out.mm_per_pixel = raw.mm_per_pixel * float(side) / float(options.size);
    }
    out.height = std::move(patch);
    if (steps) {
        steps->raw = raw.height;
        steps->contact_mask = mask;
        steps->high_passed = filtered;
        steps->smoothed = smooth ? smoothed : Image();
        steps->patch = out.height;
    }
    return out;
}

HeightMap quilt_height_maps(const std::vector<HeightMap>& patches, const QuiltOptions& options,
                            QuiltStats* stats) {
    if (patches.empty()) throw_error("quilting: no patch given");
    std::vector<Image> images;
    std::vector<std::string> names;
    HeightMap out;
    out.mm_per_pixel = patches[0].mm_per_pixel;
    out.source = patches[0].source;
    for (const HeightMap& p : patches) {
        if (p.height.channels() != 1) throw_error("{}: expected a 1-channel height map", p.source);
        if (out.mm_per_pixel > 0 && p.mm_per_pixel > 0 &&
            std::fabs(p.mm_per_pixel - out.mm_per_pixel) > 0.01f * out.mm_per_pixel)
            throw_error("{}: {} mm per pixel, but {} has {}; resample the patches to one scale first",
                        p.source,
                        p.mm_per_pixel,
                        patches[0].source,
                        out.mm_per_pixel);
        images.push_back(p.height);
        names.push_back(p.source);
        out.reference_scale_mm = std::max(out.reference_scale_mm, p.reference_scale_mm);
    }
    QuiltResult result = quilt(images, options, names);
    if (stats) *stats = result.stats;
    out.height = std::move(result.image);
    return out;
}

Image normal_map_from_height(const HeightMap& map, Amplitude amplitude, float strength) {
    if (!std::isfinite(strength) || !(strength > 0.f))  // NaN made an all-black map
        throw_error("{}: the normal strength must be a finite positive number, got {}", map.source, strength);
    if (amplitude == Amplitude::Auto)
        amplitude = map.reference_scale_mm > 0 ? Amplitude::Reference : Amplitude::Physical;
    float gain = 0;
    if (amplitude == Amplitude::Reference) {
        // Matches reference: H = height01 * scale * k with height01 = height_mm / scale, so the
        // slope per pixel is height_mm * k (spec 6.4 step 3).
        const float scale = map.reference_scale_mm > 0 ? map.reference_scale_mm : [&] {
            const auto [lo, hi] = value_range(map.height);
            return hi - lo;
        }();
        gain = reference_amplitude_factor(scale);
    } else {
        if (!(map.mm_per_pixel > 0))
            throw_error("{}: physical amplitude needs the pixel size (--mm-per-pixel)", map.source);
        gain = 1.0f / map.mm_per_pixel;
    }
    return normals_from_height(map.height, gain * strength);
}

void write_normal_map(const std::string& path, const Image& normals, float mm_per_pixel,
                      const std::string& source, int bits) {
    HeightMap info;
    info.mm_per_pixel = mm_per_pixel;
    info.source = source;
    const ImageMetadata metadata = height_map_metadata(info);
    if (lower_extension(path) == ".exr") {
        write_exr(path, normals, metadata, ExrPixelType::Float);
    } else {
        // Matches reference: floor((n * 0.5 + 0.5) * 255) (spec 6.4 step 5); 16 bits alike.
        write_png(path, encode_normals(normals), metadata, bits, Quantize::Truncate);
    }
}

void write_height_preview(const std::string& path, const Image& height) {
    Image grey = height.channels() == 1 ? height : height.channel_range(0, 1);
    const auto [lo, hi] = value_range(grey);
    const float scale = hi > lo ? 1.0f / (hi - lo) : 0.0f;
    for (float& v : grey.values()) v = (v - lo) * scale;
    write_png(path, grey, 8, Quantize::Round);
}

}  // namespace tdf
