#pragma once
/// Exit codes of `tdf` (docs/robustness.md "Errors"). `tdf batch` classifies a job's end by them
/// (docs/commands/batch.md "Failure classes"). kExitInterrupted (75) is in train/run_guard.h.

namespace tdf {

constexpr int kExitBadInput = 1;  ///< tdf::Error or a usage error: deterministic, retrying cannot help
constexpr int kExitUnexpected =
    70;  ///< an exception other than tdf::Error (sysexits' EX_SOFTWARE): a system error or a bug
constexpr int kExitOutOfMemory = 71;  ///< std::bad_alloc: the inputs need more memory than was available

}  // namespace tdf
