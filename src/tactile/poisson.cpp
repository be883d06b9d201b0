#include <tdf/tactile/poisson.h>

#include <tdf/core/error.h>
#include "fftw_plan_impl.h"

#include <algorithm>
#include <cmath>

namespace tdf {

Image integrate_gradients(const Image& gx, const Image& gy, const std::string& what) {
    const int w = gx.width(), h = gx.height();
    if (gx.channels() != 1 || gy.channels() != 1 || gy.width() != w || gy.height() != h)
        throw_error("{}: gx and gy must be 1-channel images of equal size ({}x{}x{} vs {}x{}x{})",
                    what,
                    w,
                    h,
                    gx.channels(),
                    gy.width(),
                    gy.height(),
                    gy.channels());
    if (w < 2 || h < 2) throw_error("{}: gradients must be at least 2x2, got {}x{}", what, w, h);
    if (!gx.all_finite() || !gy.all_finite()) throw_error("{}: gradients contain NaN or infinity", what);

    // Divergence of the face fluxes; boundary faces carry none (Neumann, see header).
    fftw::RealBuffer buffer = fftw::alloc_real(std::size_t(w) * std::size_t(h));
    double* f = buffer.get();
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double div = 0;
            if (x + 1 < w) div += 0.5 * (double(gx.at(x, y, 0)) + gx.at(x + 1, y, 0));
            if (x > 0) div -= 0.5 * (double(gx.at(x - 1, y, 0)) + gx.at(x, y, 0));
            if (y + 1 < h) div += 0.5 * (double(gy.at(x, y, 0)) + gy.at(x, y + 1, 0));
            if (y > 0) div -= 0.5 * (double(gy.at(x, y - 1, 0)) + gy.at(x, y, 0));
            f[std::size_t(y) * std::size_t(w) + std::size_t(x)] = div;
        }

    // Eigenvalues of the reflecting 5-point Laplacian on the DCT-II basis.
    const double pi = 3.14159265358979323846;
    fftw::solve_in_cosine_basis(f, w, h, [&](int u, int v) {
        return 2.0 * std::cos(pi * u / w) - 2.0 + 2.0 * std::cos(pi * v / h) - 2.0;
    });

    Image height(w, h, 1);
    const double normalisation = 1.0 / (4.0 * double(w) * double(h));  // REDFT10 then REDFT01
    for (std::size_t i = 0; i < height.pixel_count(); ++i) height.data()[i] = float(f[i] * normalisation);
    return height;
}

void height_gradients(const Image& height, Image& gx, Image& gy) {
    TDF_CHECK_EQ(height.channels(), 1);
    const int w = height.width(), h = height.height();
    TDF_CHECK(w >= 2 && h >= 2);
    gx = Image(w, h, 1);
    gy = Image(w, h, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, w - 1);
            const int y0 = std::max(y - 1, 0), y1 = std::min(y + 1, h - 1);
            gx.at(x, y, 0) = (height.at(x1, y, 0) - height.at(x0, y, 0)) / float(x1 - x0);
            gy.at(x, y, 0) = (height.at(x, y1, 0) - height.at(x, y0, 0)) / float(y1 - y0);
        }
}

}  // namespace tdf
