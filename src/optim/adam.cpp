#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/optim/adam.h>

#include <cmath>
#include <cstring>

namespace tdf {

namespace {

constexpr char kMagic[8] = {'T', 'D', 'F', 'A', 'D', 'A', 'M', '\0'};
constexpr std::uint32_t kVersion = 1;

template <typename T>
void append(std::string& out, const T& value) {
    out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
T take(const std::string& in, std::size_t& pos, const std::string& what) {
    if (in.size() - pos < sizeof(T)) throw_error("{}: Adam state is truncated", what);
    T value;
    std::memcpy(&value, in.data() + pos, sizeof(T));
    pos += sizeof(T);
    return value;
}

}  // namespace

std::string AdamState::blob_header(std::uint64_t parameter_count, std::int64_t step) {
    std::string out;
    out.append(kMagic, sizeof(kMagic));
    append(out, kVersion);
    append(out, parameter_count);
    append(out, step);
    return out;
}

std::uint64_t AdamState::blob_size(std::uint64_t parameter_count) {
    return sizeof(kMagic) + sizeof(kVersion) + sizeof(std::uint64_t) + sizeof(std::int64_t) +
           2 * sizeof(float) * parameter_count;
}

std::string AdamState::to_bytes() const {
    TDF_CHECK_EQ(m.size(), v.size());
    std::string out = blob_header(m.size(), step);
    out.reserve(blob_size(m.size()));
    out.append(reinterpret_cast<const char*>(m.data()), m.size() * sizeof(float));
    out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
    return out;
}

AdamState AdamState::from_bytes(const std::string& bytes, const std::string& what) {
    if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
        throw_error("{}: not an Adam state (bad magic)", what);
    std::size_t pos = sizeof(kMagic);
    const auto version = take<std::uint32_t>(bytes, pos, what);
    if (version != kVersion)
        throw_error("{}: Adam state version {} is not supported (expected {})", what, version, kVersion);
    const auto count = take<std::uint64_t>(bytes, pos, what);
    AdamState state;
    state.step = take<std::int64_t>(bytes, pos, what);
    if (state.step < 0) throw_error("{}: Adam state has a negative step count {}", what, state.step);
    const std::size_t remaining = bytes.size() - pos;
    if (count > remaining / (2 * sizeof(float)) || remaining != count * 2 * sizeof(float))
        throw_error("{}: Adam state holds {} bytes of moments, expected {} for {} parameters",
                    what,
                    remaining,
                    count * 2 * sizeof(float),
                    count);
    state.m.resize(count);
    state.v.resize(count);
    std::memcpy(state.m.data(), bytes.data() + pos, count * sizeof(float));
    std::memcpy(state.v.data(), bytes.data() + pos + count * sizeof(float), count * sizeof(float));
    return state;
}

bool AdamState::operator==(const AdamState& other) const {
    // Bitwise comparison (so NaN moments compare equal to themselves after a round trip).
    return step == other.step && m.size() == other.m.size() && v.size() == other.v.size() &&
           std::memcmp(m.data(), other.m.data(), m.size() * sizeof(float)) == 0 &&
           std::memcmp(v.data(), other.v.data(), v.size() * sizeof(float)) == 0;
}

Adam::Adam(std::size_t parameter_count, const AdamHyperparams& hyper) : m_hyper(hyper) {
    m_state.m.assign(parameter_count, 0.0f);
    m_state.v.assign(parameter_count, 0.0f);
}

void Adam::restore(AdamState state) {
    if (state.m.size() != m_state.m.size() || state.v.size() != m_state.v.size())
        throw_error("Adam state for {} parameters cannot be restored into an optimizer for {}",
                    state.m.size(),
                    m_state.m.size());
    m_state = std::move(state);
}

void Adam::step(std::vector<float>& parameters, const std::vector<float>& gradient) {
    TDF_CHECK_EQ(parameters.size(), m_state.m.size());
    TDF_CHECK_EQ(gradient.size(), m_state.m.size());
    m_state.step += 1;
    // Matches torch (single-tensor path): the bias corrections are Python floats (double),
    // step_size = lr / bc1 and the denominator is sqrt(v) / sqrt(bc2) + eps, in float32.
    const double bias1 = 1.0 - std::pow(double(m_hyper.beta1), double(m_state.step));
    const double bias2 = 1.0 - std::pow(double(m_hyper.beta2), double(m_state.step));
    const float step_size = float(double(m_hyper.learning_rate) / bias1);
    const float bias2_sqrt = float(std::sqrt(bias2));
    const float b1 = m_hyper.beta1, b2 = m_hyper.beta2, eps = m_hyper.epsilon;
    float* p = parameters.data();
    float* m = m_state.m.data();
    float* v = m_state.v.data();
    const float* g = gradient.data();
    parallel_for(parameters.size(), 16384, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            m[i] = b1 * m[i] + (1.0f - b1) * g[i];
            v[i] = b2 * v[i] + (1.0f - b2) * g[i] * g[i];
            p[i] -= step_size * m[i] / (std::sqrt(v[i]) / bias2_sqrt + eps);
        }
    });
}

}  // namespace tdf
