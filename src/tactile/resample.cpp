#include <tdf/tactile/resample.h>

#include <tdf/core/error.h>

#include <algorithm>

namespace tdf {

Image crop(const Image& image, int x, int y, int width, int height) {
    TDF_CHECK(x >= 0 && y >= 0 && width >= 0 && height >= 0);
    TDF_CHECK(x + width <= image.width() && y + height <= image.height());
    const int c = image.channels();
    Image out(width, height, c);
    for (int row = 0; row < height; ++row)
        std::copy(image.pixel(x, y + row),
                  image.pixel(x, y + row) + std::size_t(width) * std::size_t(c),
                  out.pixel(0, row));
    return out;
}

}  // namespace tdf
