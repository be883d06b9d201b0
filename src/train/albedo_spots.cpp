#include <tdf/train/albedo_spots.h>

#include <tdf/core/error.h>

#include <algorithm>
#include <limits>

namespace tdf {

std::vector<AlbedoSpot> find_albedo_spots(const Image& input, const std::vector<int>& label, int size) {
    const int w = input.width(), h = input.height();
    TDF_CHECK(input.channels() == 3 && label.size() == input.pixel_count() && size > 0);
    AlbedoSpot dark{"dark", 0, 0, size, std::numeric_limits<double>::max()};
    AlbedoSpot bright{"bright", 0, 0, size, -1.0};
    const int stride = std::max(1, size / 4);
    for (int y = 0; y + size <= h; y += stride)
        for (int x = 0; x + size <= w; x += stride) {
            const int chart = label[std::size_t(y) * std::size_t(w) + std::size_t(x)];
            if (chart < 0) continue;
            double sum = 0;
            bool one_chart = true;
            for (int v = y; v < y + size && one_chart; ++v)
                for (int u = x; u < x + size; ++u) {
                    const std::size_t t = std::size_t(v) * std::size_t(w) + std::size_t(u);
                    if (label[t] != chart) {
                        one_chart = false;
                        break;
                    }
                    const float* c = input.data() + 3 * t;
                    sum += 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
                }
            if (!one_chart) continue;
            const double mean = sum / (double(size) * double(size));
            if (mean < dark.luminance) dark.x = x, dark.y = y, dark.luminance = mean;
            if (mean > bright.luminance) bright.x = x, bright.y = y, bright.luminance = mean;
        }
    std::vector<AlbedoSpot> spots;
    if (bright.luminance >= 0) spots = {dark, bright};
    return spots;
}

Image albedo_spot_crop(const AlbedoSpot& spot, const Image& map) {
    TDF_CHECK(map.channels() == 3 && spot.size > 0 && spot.x >= 0 && spot.y >= 0 &&
              spot.x + spot.size <= map.width() && spot.y + spot.size <= map.height());
    Image crop(spot.size, spot.size, 3);
    for (int y = 0; y < spot.size; ++y)
        std::copy_n(map.pixel(spot.x, spot.y + y), 3 * std::size_t(spot.size), crop.pixel(0, y));
    return crop;
}

Image albedo_spot_strip(const Image& input_crop, const Image& matched_crop, const Image& final_crop, int zoom) {
    TDF_CHECK(zoom >= 1);
    const int size = input_crop.width();
    for (const Image* crop : {&input_crop, &matched_crop, &final_crop})
        TDF_CHECK(crop->width() == size && crop->height() == size && crop->channels() == 3);
    constexpr int kGap = 4;
    const int side = size * zoom;
    Image strip(3 * side + 2 * kGap, side, 3, 1.0f);
    const Image* crops[] = {&input_crop, &matched_crop, &final_crop};
    for (int k = 0; k < 3; ++k)
        for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x)
                for (int c = 0; c < 3; ++c)
                    strip.at(k * (side + kGap) + x, y, c) = std::clamp(crops[k]->at(x / zoom, y / zoom, c), 0.0f, 1.0f);
    return strip;
}

}  // namespace tdf
