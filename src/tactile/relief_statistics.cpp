#include <tdf/tactile/relief_statistics.h>

#include <tdf/core/error.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

class TiltCounter {
public:
    explicit TiltCounter(const TiltHistogramOptions& options) : m_options(options), m_counts(std::size_t(options.bins), 0.0) {
        TDF_CHECK(options.bins > 0 && options.max_degrees > 0.0f);
    }
    void add(Vec3f n) {
        const float length = tdf::length(n);
        if (!(length > 0.0f)) return;
        const float tilt = degrees(std::acos(std::clamp(n.z / length, -1.0f, 1.0f)));
        const int bin = std::min(m_options.bins - 1, int(tilt / m_options.max_degrees * float(m_options.bins)));
        m_counts[std::size_t(bin)] += 1.0;
        m_total += 1.0;
    }
    std::vector<double> histogram() && {
        if (m_total > 0)
            for (double& c : m_counts) c /= m_total;
        return std::move(m_counts);
    }

private:
    TiltHistogramOptions m_options;
    std::vector<double> m_counts;
    double m_total = 0;
};

}  // namespace

std::vector<double> tilt_histogram(const Vec3f* normals, std::size_t count, const TiltHistogramOptions& options) {
    TiltCounter counter(options);
    for (std::size_t i = 0; i < count; ++i) counter.add(normals[i]);
    return std::move(counter).histogram();
}

std::vector<double> tilt_histogram(const Image& normals, const TiltHistogramOptions& options) {
    TDF_CHECK(normals.channels() >= 3);
    TiltCounter counter(options);
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        const float* n = normals.data() + p * std::size_t(normals.channels());
        counter.add({n[0], n[1], n[2]});
    }
    return std::move(counter).histogram();
}

double histogram_l1_distance(const std::vector<double>& a, const std::vector<double>& b) {
    TDF_CHECK_EQ(a.size(), b.size());
    double d = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) d += std::abs(a[i] - b[i]);
    return d;
}

}  // namespace tdf
