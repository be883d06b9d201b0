#pragma once
/// `tdf optimize` as a library call: load the scene, train, checkpoint, export. Everything a
/// run writes goes under `output_dir` (README "tdf optimize" lists the files).
#include <string>
#include <vector>

namespace tdf {

struct OptimizeOptions {
    std::string scene_path;
    std::vector<std::string> overrides;  ///< `key=value` scene overrides
    std::string output_dir;
    std::string name;                    ///< file prefix; default: the scene file's folder name
    bool resume = false;                 ///< continue from `<output_dir>/checkpoint.bin`
    /// Stop (with a checkpoint) once this many iterations are done, 0 = run to the end. For
    /// batch schedulers with time limits: run in slices, each continuing with `resume`.
    int stop_after = 0;
};

/// Runs the whole job; throws tdf::Error on bad input or a failed run (the last good
/// checkpoint stays on disk and the message says how to resume).
void run_optimize(const OptimizeOptions& options);

}  // namespace tdf
