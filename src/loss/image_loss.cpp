#include <tdf/core/error.h>
#include <tdf/core/image_ops.h>
#include <tdf/loss/image_loss.h>

#include <cmath>
#include <vector>

#include "ordered_sum_impl.h"

namespace tdf {

using detail::elementwise;
using detail::ordered_sum;

namespace {

// Squared error over `count` values, value i weighted by mask_of(i) on both sides (the
// reference's MSE(M pred, M target)).
template <typename MaskOf>
double mse_impl(const float* pred, const float* target, std::size_t count, float* grad, float weight, MaskOf mask_of) {
    if (count == 0) return 0.0;
    // The gradient needs no sum: both in one pass over the values.
    const float scale = float(2.0 * double(weight) / double(count));
    const double sum = ordered_sum(count, [&](std::size_t b, std::size_t e) {
        double s = 0;
        for (std::size_t i = b; i < e; ++i) {
            const float m = mask_of(i);
            const double d = double(m) * (double(pred[i]) - double(target[i]));
            s += d * d;
            if (grad) grad[i] += scale * m * m * (pred[i] - target[i]);
        }
        return s;
    });
    return sum / double(count);
}

}  // namespace

double mse_loss(const float* pred, const float* target, std::size_t count, float* grad, float weight) {
    return mse_impl(pred, target, count, grad, weight, [](std::size_t) { return 1.0f; });
}

double masked_mse_loss(const float* pred, const float* target, const float* mask, int channels, std::size_t count,
                       float* grad, float weight) {
    const std::size_t c = std::size_t(channels);
    return mse_impl(pred, target, count * c, grad, weight, [&](std::size_t i) { return mask[i / c]; });
}

double l1_loss(const float* pred, const float* target, std::size_t count, float* grad, float weight) {
    if (count == 0) return 0.0;
    const float scale = float(double(weight) / double(count));
    const double sum = ordered_sum(count, [&](std::size_t b, std::size_t e) {
        double s = 0;
        for (std::size_t i = b; i < e; ++i) {
            s += std::abs(double(pred[i]) - double(target[i]));
            if (!grad) continue;
            const float d = pred[i] - target[i];
            grad[i] += d > 0 ? scale : (d < 0 ? -scale : 0.0f);
        }
        return s;
    });
    return sum / double(count);
}

double mean_colour_mse_loss(const float* pred, const float* target, const ImageBatchShape& shape, float* grad,
                            float weight) {
    const std::size_t pixels = shape.pixels(), channels = std::size_t(shape.channels);
    const std::size_t groups = std::size_t(shape.images) * channels;
    if (groups == 0 || pixels == 0) return 0.0;
    // Per (image, channel) mean difference; images are few, so each is summed serially in
    // pixel order (deterministic), images in parallel.
    std::vector<double> diff(groups, 0.0);
    parallel_for(std::size_t(shape.images), 1, [&](std::size_t i0, std::size_t i1) {
        for (std::size_t img = i0; img < i1; ++img) {
            const float* p = pred + img * pixels * channels;
            const float* t = target + img * pixels * channels;
            for (std::size_t c = 0; c < channels; ++c) {
                double s = 0;
                for (std::size_t k = 0; k < pixels; ++k)
                    s += double(p[k * channels + c]) - double(t[k * channels + c]);
                diff[img * channels + c] = s / double(pixels);
            }
        }
    });
    double loss = 0;
    for (const double d : diff) loss += d * d;
    loss /= double(groups);
    if (grad) {
        // dL/dpred = 2 (mean_p - mean_t) / groups / pixels, the same for every pixel of a group.
        std::vector<float> g(groups);
        for (std::size_t k = 0; k < groups; ++k)
            g[k] = float(2.0 * double(weight) * diff[k] / double(groups) / double(pixels));
        elementwise(shape.values(), [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) {
                const std::size_t img = i / (pixels * channels), c = i % channels;
                grad[i] += g[img * channels + c];
            }
        });
    }
    return loss;
}

float cosine_similarity(Vec3f x, Vec3f y, float eps) {
    return dot(x, y) / std::max(length(x) * length(y), eps);
}

namespace {

constexpr float kCosineEps = 1e-8f;

// d cos(x, y) / dx for cos = x.y / max(|x||y|, eps).
inline Vec3f cosine_gradient(Vec3f x, Vec3f y) {
    const float lx = length(x), ly = length(y);
    const float denom = lx * ly;
    if (denom <= kCosineEps) return y / kCosineEps;
    const float c = dot(x, y) / denom;
    return y / denom - x * (c / (lx * lx));
}

double masked_cosine_impl(const Vec3f* pred, const Vec3f* target, const float* mask, std::size_t count,
                          Vec3f* grad, float weight) {
    if (count == 0) return 0.0;
    const float scale = -weight / float(count);
    const double sum = ordered_sum(count, [&](std::size_t b, std::size_t e) {
        double s = 0;
        for (std::size_t i = b; i < e; ++i) {
            const float m = mask ? mask[i] : 1.0f;
            s += double(cosine_similarity(pred[i] * m, target[i] * m, kCosineEps));
            if (grad && m != 0.0f) grad[i] += cosine_gradient(pred[i] * m, target[i] * m) * (scale * m);
        }
        return s;
    });
    return 1.0 - sum / double(count);
}

}  // namespace

double cosine_loss(const Vec3f* pred, const Vec3f* target, std::size_t count, Vec3f* grad, float weight) {
    return masked_cosine_impl(pred, target, nullptr, count, grad, weight);
}

double masked_cosine_loss(const Vec3f* pred, const Vec3f* target, const float* mask, std::size_t count,
                          Vec3f* grad, float weight) {
    return masked_cosine_impl(pred, target, mask, count, grad, weight);
}

namespace {

constexpr int kSsimRadius = 5;  // 11 taps
constexpr float kSsimSigma = 1.5f;
constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;

// Separable Gaussian blur of interleaved images, zero padding (Border), same size. The kernel is
// symmetric, so this zero-padded correlation is its own adjoint (used by the backward pass).
class GaussianBlur {
public:
    explicit GaussianBlur(const ImageBatchShape& shape)
        : m_shape(shape), m_taps(gaussian_kernel<float>(kSsimSigma, kSsimRadius)) {}

    void operator()(const float* in, float* out) const {
        const std::size_t image_values = m_shape.pixels() * std::size_t(m_shape.channels);
        for (int i = 0; i < m_shape.images; ++i)
            convolve_separable(ConstImageView(in + std::size_t(i) * image_values, m_shape.width, m_shape.height,
                                              m_shape.channels),
                               ImageView(out + std::size_t(i) * image_values, m_shape.width, m_shape.height,
                                         m_shape.channels),
                               m_taps,
                               Addressing::Border);
    }

private:
    ImageBatchShape m_shape;
    std::vector<float> m_taps;
};

}  // namespace

double ssim_loss(const float* pred, const float* target, const ImageBatchShape& shape, float* grad,
                 float weight) {
    const std::size_t n = shape.values();
    if (n == 0) return 0.0;
    GaussianBlur blur(shape);
    std::vector<float> mu_x(n), mu_y(n), e_xx(n), e_yy(n), e_xy(n), buffer(n);
    blur(pred, mu_x.data());
    blur(target, mu_y.data());
    elementwise(n, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) buffer[i] = pred[i] * pred[i];
    });
    blur(buffer.data(), e_xx.data());
    elementwise(n, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) buffer[i] = target[i] * target[i];
    });
    blur(buffer.data(), e_yy.data());
    elementwise(n, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) buffer[i] = pred[i] * target[i];
    });
    blur(buffer.data(), e_xy.data());

    // Per pixel: S = A1 A2 / (B1 B2) with A1 = 2 mx my + C1, A2 = 2 sxy + C2,
    // B1 = mx^2 + my^2 + C1, B2 = sxx + syy + C2. The backward needs dS/dmx, dS/dsxx, dS/dsxy;
    // they overwrite e_xx, e_yy, e_xy in place (a = dS/dmx - 2 dS/dsxx mx - dS/dsxy my).
    const double sum = ordered_sum(n, [&](std::size_t b, std::size_t e) {
        double s = 0;
        for (std::size_t i = b; i < e; ++i) {
            const double mx = mu_x[i], my = mu_y[i];
            const double sxx = e_xx[i] - mx * mx, syy = e_yy[i] - my * my, sxy = e_xy[i] - mx * my;
            const double a1 = 2 * mx * my + kC1, a2 = 2 * sxy + kC2;
            const double b1 = mx * mx + my * my + kC1, b2 = sxx + syy + kC2;
            const double ssim = a1 * a2 / (b1 * b2);
            s += ssim;
            if (grad) {
                const double d_mx = 2 * my * a2 / (b1 * b2) - ssim * 2 * mx / b1;
                const double d_sxx = -ssim / b2;
                const double d_sxy = 2 * a1 / (b1 * b2);
                e_xx[i] = float(d_mx - 2 * d_sxx * mx - d_sxy * my);
                e_yy[i] = float(d_sxx);
                e_xy[i] = float(d_sxy);
            }
        }
        return s;
    });
    if (grad) {
        // dS/dx_q = blur(a)_q + 2 x_q blur(dS/dsxx)_q + y_q blur(dS/dsxy)_q; L = 1 - mean S.
        blur(e_xx.data(), mu_x.data());
        blur(e_yy.data(), mu_y.data());
        blur(e_xy.data(), buffer.data());
        const float scale = -weight / float(n);
        elementwise(n, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i)
                grad[i] += scale * (mu_x[i] + 2.0f * pred[i] * mu_y[i] + target[i] * buffer[i]);
        });
    }
    return 1.0 - sum / double(n);
}

}  // namespace tdf
