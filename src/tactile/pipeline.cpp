#include <tdf/tactile/pipeline.h>

#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/contact_mask.h>
#include <tdf/tactile/high_pass.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/core/image_ops.h>
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

namespace {

// Base slope gain (per height unit per pixel) of physical amplitude: 1 for heights in pixel
// widths, 1 / mm_per_pixel, or 1 (1 mm per pixel) when the size is unknown.
float physical_gain(const HeightMap& map) {
    if (map.pixel_heights) return 1.0f;
    return map.mm_per_pixel > 0 ? 1.0f / map.mm_per_pixel : 1.0f;
}

// A 0/1 mask resampled like its image: Lanczos, then thresholded at one half.
Image resample_mask(const Image& mask, int width, int height) {
    Image out = resize_lanczos(mask, width, height);
    for (float& v : out.values()) v = v >= 0.5f ? 1.0f : 0.0f;
    return out;
}

}  // namespace

HeightMap extract_patch(const HeightInput& input, const PatchOptions& options, PatchSteps* steps) {
    const HeightMap& raw = input.map;
    const std::string& what = raw.source;
    const bool known_size = raw.mm_per_pixel > 0;
    HighPass high_pass = options.high_pass;
    float cutoff_mm = options.cutoff_mm;
    if (high_pass == HighPass::Auto) {
        high_pass = input.from_normals ? HighPass::Gaussian : HighPass::FftBlock;
        const int width = std::min(raw.height.width(), raw.height.height());
        cutoff_mm = 0.25f * float(width) * (known_size ? raw.mm_per_pixel : 1.0f);
    } else if (high_pass == HighPass::Gaussian && !known_size) {
        throw_error("{}: a Gaussian cut-off in mm needs the pixel size (--mm-per-pixel or --size-mm)", what);
    }
    // The reference smooths captures; other inputs keep their finest detail (a 5 px bilateral
    // with the reference's sigmas is nearly a box filter, which flattens fine relief).
    bool smooth = options.smooth == Toggle::On || (options.smooth == Toggle::Auto && input.capture);
    const bool contact = options.contact == Toggle::On || (options.contact == Toggle::Auto && input.capture);
    Image filtered;
    switch (high_pass) {
        case HighPass::FftBlock:
            filtered = high_pass_fft_block(raw.height, options.freq_threshold);
            break;
        case HighPass::Gaussian:
            filtered = high_pass_gaussian(raw.height, cutoff_mm, known_size ? raw.mm_per_pixel : 1.0f);
            break;
        case HighPass::Auto:  // resolved above
        case HighPass::None:
            filtered = raw.height;
            break;
    }
    int x = 0, y = 0, width = raw.height.width(), height = raw.height.height();
    Image mask, region;
    if (contact) {
        ContactRegion found = find_contact_region(raw.height, options.depth_threshold, what);
        x = found.x, y = found.y, width = height = found.side;
        mask = std::move(found.mask);
        region = mask;
    }
    int diameter = smooth ? options.bilateral_diameter : 0;
    Image smoothed = smooth ? bilateral_filter(filtered, diameter, options.sigma_color, options.sigma_space) : filtered;
    double full_window_loss = 0;
    if (smooth && options.smooth == Toggle::Auto) {
        // The window must be small against the texture's period: narrow it until the smoothing
        // takes at most kSmoothingMaxTiltLoss of the contact region's detail tilt.
        const auto [crop_lo, crop_hi] = value_range(crop(filtered, x, y, width, height));
        const float gain = reference_amplitude_factor(crop_hi - crop_lo);
        const double before =
            material_statistics(detail_slopes(normals_from_height(filtered, gain)), mask, 90.0).mean_tilt;
        auto loss = [&](const Image& candidate) {
            const double after =
                material_statistics(detail_slopes(normals_from_height(candidate, gain)), mask, 90.0).mean_tilt;
            return before > 0 ? 1.0 - after / before : 0.0;
        };
        double current = loss(smoothed);
        if (current > kSmoothingMaxTiltLoss) full_window_loss = current;
        while (current > kSmoothingMaxTiltLoss && diameter > 1) {
            diameter -= 2;
            smoothed = diameter > 1 ? bilateral_filter(filtered, diameter, options.sigma_color, options.sigma_space)
                                    : filtered;
            current = diameter > 1 ? loss(smoothed) : 0.0;
        }
        if (diameter <= 1) diameter = 0, smooth = false;
    }
    Image patch = crop(smoothed, x, y, width, height);
    // Matches reference: the amplitude `scale` is the crop's range before resampling (spec 6.2 step 6).
    const auto [lo, hi] = value_range(patch);
    if (!(hi - lo > 1e-6f))
        throw_error(
            "{}: the patch is flat (height range {} mm); nothing to turn into a texture", what, hi - lo);
    for (float& v : patch.values()) v -= lo;
    HeightMap out;
    out.source = raw.source;
    out.pixel_heights = raw.pixel_heights;
    // Only captures take the reference's amplitude rule; every other input keeps its true
    // slopes (normal_map_from_height, Amplitude::Auto).
    if (input.capture) out.reference_scale_mm = hi - lo, out.reference_mm_per_pixel = raw.mm_per_pixel;
    out.mm_per_pixel = raw.mm_per_pixel;

    // The input's normals at the patch's amplitude (strength 1), and where its texture lies.
    Image input_normals = input.from_normals && !input.normals.empty()
                              ? input.normals
                              : normals_from_height(raw.height,
                                                    input.capture ? reference_amplitude_factor(hi - lo)
                                                                  : physical_gain(raw));
    if (region.empty()) region = texture_region(detail_slopes(input_normals).tilt);
    Image patch_mask = crop(region, x, y, width, height);

    const int size = options.size < 0 ? (input.capture ? 256 : 0) : options.size;
    if (size > 0 && (size != width || size != height)) {
        patch = resize_lanczos(patch, size, size);
        patch_mask = resample_mask(patch_mask, size, size);
        if (out.mm_per_pixel > 0) out.mm_per_pixel = raw.mm_per_pixel * float(width) / float(size);
        if (out.pixel_heights) {  // heights in pixel widths follow the pixel
            const float factor = float(size) / float(width);
            for (float& v : patch.values()) v *= factor;
        }
    }
    out.height = std::move(patch);
    out.texture_mask = std::move(patch_mask);
    if (steps) {
        steps->raw = raw.height;
        steps->contact_mask = mask;
        steps->high_passed = filtered;
        steps->smoothed = smooth ? smoothed : Image();
        steps->bilateral_diameter = diameter;
        steps->full_window_tilt_loss = full_window_loss;
        steps->patch = out.height;
        steps->region = std::move(region);
        steps->input_normals = std::move(input_normals);
    }
    return out;
}

HeightMap quilt_height_maps(const std::vector<HeightMap>& patches, const QuiltOptions& options,
                            QuiltStats* stats, Image* seams) {
    if (patches.empty()) throw_error("quilting: no patch given");
    std::vector<Image> images, masks;
    std::vector<std::string> names;
    HeightMap out;
    out.mm_per_pixel = patches[0].mm_per_pixel;
    out.reference_mm_per_pixel = patches[0].reference_mm_per_pixel;  // their pixels agree within 1 %
    out.pixel_heights = patches[0].pixel_heights;
    out.source = patches[0].source;
    for (const HeightMap& p : patches) {
        if (p.height.channels() != 1) throw_error("{}: expected a 1-channel height map", p.source);
        if (p.pixel_heights != out.pixel_heights)
            throw_error("{}: its pixel size is {}, but {} has {}; give both the same --mm-per-pixel",
                        p.source,
                        p.mm_per_pixel > 0 ? fmt::format("{} mm", p.mm_per_pixel) : std::string("unknown"),
                        patches[0].source,
                        out.mm_per_pixel > 0 ? fmt::format("{} mm", out.mm_per_pixel) : std::string("unknown"));
        if (out.mm_per_pixel > 0 && p.mm_per_pixel > 0 &&
            std::fabs(p.mm_per_pixel - out.mm_per_pixel) > 0.01f * out.mm_per_pixel)
            throw_error("{}: {} mm per pixel, but {} has {}; resample the patches to one scale first",
                        p.source,
                        p.mm_per_pixel,
                        patches[0].source,
                        out.mm_per_pixel);
        images.push_back(p.height);
        masks.push_back(p.texture_mask);
        names.push_back(p.source);
        out.reference_scale_mm = std::max(out.reference_scale_mm, p.reference_scale_mm);
    }
    QuiltResult result = quilt(images, options, names, masks);
    if (stats) *stats = result.stats;
    if (seams) *seams = std::move(result.seams);
    out.height = std::move(result.image);
    out.tileable = options.tileable;
    return out;
}

HeightMap optimize_height_maps(const std::vector<HeightMap>& patches, const HeightMap& initial,
                               TextureOptimizationOptions options) {
    std::vector<Image> images, masks;
    for (const HeightMap& p : patches) images.push_back(p.height), masks.push_back(p.texture_mask);
    options.tileable = initial.tileable;
    HeightMap out = initial;
    out.height = optimize_texture(images, masks, initial.height, options);
    return out;
}

bool slopes_known(const HeightMap& map, Amplitude amplitude) {
    if (amplitude == Amplitude::Auto)
        amplitude = map.reference_scale_mm > 0 ? Amplitude::Reference : Amplitude::Physical;
    return amplitude == Amplitude::Reference || map.pixel_heights || map.mm_per_pixel > 0;
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
        // Per pixel of the capture, not of the resampled patch: resampling keeps the slopes.
        if (map.reference_mm_per_pixel > 0 && map.mm_per_pixel > 0)
            gain *= map.reference_mm_per_pixel / map.mm_per_pixel;
    } else {
        gain = physical_gain(map);
    }
    return normals_from_height(map.height, gain * strength, map.tileable);
}

float auto_strength(const HeightMap& map, Amplitude amplitude) {
    // Known slopes are the material's, however gentle: a wood veneer's 0.75 degrees made 8
    // would be 11 times steeper than its input (issue 28). `--bits auto` keeps them in 16 bits
    // when 8 would not.
    if (slopes_known(map, amplitude)) return 1.0f;
    const DetailSlopes detail = detail_slopes(normal_map_from_height(map, amplitude, 1.0f));
    Image mask = map.texture_mask.empty() ? texture_region(detail.tilt) : map.texture_mask;
    const double mean = material_statistics(detail, mask, 90.0).mean_tilt;
    // Mean of atan(g |s|) grows with g: bisect in log space for the target.
    std::vector<double> magnitude;
    for (std::size_t p = 0; p < detail.tilt.pixel_count(); ++p)
        if (mask.data()[p] != 0.0f)
            magnitude.push_back(std::hypot(double(detail.slopes.data()[2 * p]), double(detail.slopes.data()[2 * p + 1])));
    if (magnitude.empty() || !(mean > 0)) return 1.0f;
    auto tilt_at = [&](double g) {
        double sum = 0;
        for (double m : magnitude) sum += std::atan(g * m);
        return sum / double(magnitude.size()) * 180.0 / 3.14159265358979323846;
    };
    double lo = 1e-6, hi = 1e6;
    for (int i = 0; i < 100; ++i) {
        const double mid = std::sqrt(lo * hi);
        (tilt_at(mid) < kAutoStrengthTilt ? lo : hi) = mid;
    }
    return float(std::sqrt(lo * hi));
}

Image compared_input_normals(const PatchSteps& steps, const HeightMap& patch, Amplitude amplitude, float strength) {
    return slopes_known(patch, amplitude) ? steps.input_normals : scale_normal_slopes(steps.input_normals, strength);
}

void write_normal_map(const std::string& path, const Image& normals, float mm_per_pixel,
                      const std::string& source, int bits, const ImageMetadata& extra) {
    HeightMap info;
    info.mm_per_pixel = mm_per_pixel;
    info.source = source;
    ImageMetadata metadata = height_map_metadata(info);
    for (const auto& [key, value] : extra) metadata[key] = value;
    if (lower_extension(path) == ".exr") {
        write_exr(path, normals, metadata, ExrPixelType::Float);
    } else {
        // Matches reference: floor((n * 0.5 + 0.5) * 255) (spec 6.4 step 5); 16 bits alike.
        write_png(path, encode_normals(normals), metadata, bits, Quantize::Truncate);
    }
}

void write_height_preview_png(const std::string& path, const HeightMap& map) {
    const auto [lo, hi] = value_range(map.height);
    Image grey = map.height;
    const float scale = hi > lo ? 1.0f / (hi - lo) : 0.0f;
    for (float& v : grey.values()) v = (v - lo) * scale;
    ImageMetadata metadata = height_map_metadata(map);
    metadata[kMetaHeightMin] = fmt::format("{}", lo);
    metadata[kMetaHeightMax] = fmt::format("{}", hi);
    write_png(path, grey, metadata, 16, Quantize::Round);
}

void write_height_preview(const std::string& path, const Image& height) {
    Image grey = height.channels() == 1 ? height : height.channel_range(0, 1);
    const auto [lo, hi] = value_range(grey);
    const float scale = hi > lo ? 1.0f / (hi - lo) : 0.0f;
    for (float& v : grey.values()) v = (v - lo) * scale;
    write_png(path, grey, 8, Quantize::Round);
}

}  // namespace tdf
