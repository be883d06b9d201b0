#pragma once
/// One binary file holding the field parameters, the Adam state and the caller's extra bytes
/// (for instance a JSON object with the iteration and RNG states), so a run can resume exactly.
///
/// Layout (little-endian): magic "TDFCKPT\0", u32 version (1), u32 reserved (0),
/// u64 parameter count, u64 Adam blob size, u64 extra size, parameters (float32),
/// Adam blob (AdamState::to_bytes), extra bytes, u64 FNV-1a checksum of everything before it.
/// Written atomically (temporary file, then rename), so a crash never leaves a half file.
#include <tdf/optim/adam.h>

#include <string>
#include <vector>

namespace tdf {

struct FieldCheckpoint {
    std::vector<float> parameters;
    AdamState adam;
    std::string extra;  ///< opaque to this module
};

/// Consecutive floats owned elsewhere; `data == nullptr` stands for `size` zeros.
struct FloatRange {
    const float* data = nullptr;
    std::size_t size = 0;
};

/// What a checkpoint holds, as pieces that are written one after the other (parameters, then
/// the first moments, then the second), so that a trainer whose values live in several arrays
/// never concatenates them: the file is streamed, and the peak memory of a run does not grow.
struct CheckpointPieces {
    std::vector<FloatRange> parameters, m, v;  ///< m and v add up to as many values as parameters
    std::int64_t step = 0;                     ///< Adam's step count
};

/// Writes `path` atomically; throws tdf::Error when it cannot be written (disk full, ...).
void save_field_checkpoint(const std::string& path, const std::vector<float>& parameters,
                           const AdamState& adam, const std::string& extra = {});
/// The same file from pieces (byte-identical to the concatenated form).
void save_field_checkpoint(const std::string& path, const CheckpointPieces& pieces, const std::string& extra = {});

/// Reads a checkpoint; throws tdf::Error naming `path` when it is missing, not a checkpoint,
/// of another version, truncated, or fails its checksum.
FieldCheckpoint load_field_checkpoint(const std::string& path);

}  // namespace tdf
