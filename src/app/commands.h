#pragma once
// Each subcommand lives in cmd_<name>.cpp and registers itself here: its options on a CLI11
// subcommand and a function returning the process exit code. main() only parses and dispatches.
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace tdf::app {

struct Command {
    CLI::App* app = nullptr;
    std::function<int()> run;
};

/// Options every subcommand accepts, set before the command runs.
struct GlobalOptions {
    int threads = 0;  ///< 0 = all cores (or SLURM_CPUS_PER_TASK)
    bool quiet = false;
    bool verbose = false;
};

Command register_render(CLI::App& root);
Command register_compare(CLI::App& root);
Command register_tactile(CLI::App& root);
/// `tdf tactile simulate` (cmd_tactile_simulate.cpp): a step of `tdf tactile`, on its parent.
Command register_tactile_simulate(CLI::App& tactile);
Command register_atlas(CLI::App& root);
Command register_optimize(CLI::App& root);
Command register_batch(CLI::App& root);
Command register_parts(CLI::App& root);

}  // namespace tdf::app
