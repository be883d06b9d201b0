#pragma once
/// Adam (Kingma & Ba 2015) exactly as `torch.optim.Adam` with default flags (spec 4.4):
/// dense update of every parameter each step (parameters whose gradient is 0 still move while
/// their moments are non-zero), explicit bias correction, no weight decay, no amsgrad.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tdf {

/// Hyper-parameters; the defaults are the reference's (`texture_lr`, torch defaults).
struct AdamHyperparams {
    float learning_rate = 0.01f;
    float beta1 = 0.9f;
    float beta2 = 0.999f;
    float epsilon = 1e-8f;
};

/// Optimizer state: first and second moments per parameter and the number of steps taken.
struct AdamState {
    std::vector<float> m;
    std::vector<float> v;
    std::int64_t step = 0;

    /// Serializes to a self-describing little-endian binary blob (magic, version, sizes), then
    /// the moments m and v as float32.
    std::string to_bytes() const;
    /// The blob's bytes before the moments, for writers that stream m and v from elsewhere.
    static std::string blob_header(std::uint64_t parameter_count, std::int64_t step);
    /// The size of to_bytes() for `parameter_count` moments.
    static std::uint64_t blob_size(std::uint64_t parameter_count);
    /// Parses `to_bytes()` output; `what` names the source in errors. Throws tdf::Error on a
    /// wrong magic/version, truncated data or inconsistent sizes.
    static AdamState from_bytes(const std::string& bytes, const std::string& what);

    bool operator==(const AdamState& other) const;
};

class Adam {
public:
    /// An optimizer for `parameter_count` parameters with zero moments.
    explicit Adam(std::size_t parameter_count, const AdamHyperparams& hyper = {});

    const AdamHyperparams& hyperparams() const { return m_hyper; }
    const AdamState& state() const { return m_state; }
    /// Replaces the state (resume). Throws tdf::Error when its sizes do not match.
    void restore(AdamState state);

    /// One step: step += 1; m = b1 m + (1-b1) g; v = b2 v + (1-b2) g^2;
    /// p -= lr / (1 - b1^step) * m / (sqrt(v) / sqrt(1 - b2^step) + eps), in parallel
    /// (elementwise, so bit-identical on any thread count). Sizes must equal parameter_count.
    void step(std::vector<float>& parameters, const std::vector<float>& gradient);

private:
    AdamHyperparams m_hyper;
    AdamState m_state;
};

}  // namespace tdf
