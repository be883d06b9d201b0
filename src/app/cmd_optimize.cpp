// tdf optimize: learn aligned albedo and tactile normal textures for a mesh (docs/commands/optimize.md).
#include "commands.h"

#include <tdf/train/optimize_run.h>
#include <tdf/train/run_guard.h>

namespace tdf::app {

Command register_optimize(CLI::App& root) {
    auto options = std::make_shared<OptimizeOptions>();
    Command command;
    CLI::App* app = root.add_subcommand(
        "optimize", "learn an albedo map and a tactile normal map for a mesh from a scene file, and export the asset");
    app->add_option("scene", options->scene_path, "scene file (JSON)")->required()->check(CLI::ExistingFile);
    app->add_option("overrides", options->overrides, "scene overrides key=value (e.g. optimize.iterations=50 seed=7)");
    app->add_option("-o,--output", options->output_dir, "output folder")->required();
    app->add_option("--name", options->name, "file name prefix (default: the scene's folder name)");
    app->add_flag("--resume", options->resume, "continue an interrupted run from <output>/checkpoint.bin");
    app->add_option("--stop-after", options->stop_after,
                    "stop with a checkpoint after this many iterations (0 = run to the end); continue with --resume")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    command.app = app;
    command.run = [options] {
        const StopSignals stop_signals;  // SIGTERM/SIGINT/SIGUSR1: checkpoint, exit kExitInterrupted (main.cpp)
        run_optimize(*options);
        return 0;
    };
    return command;
}

}  // namespace tdf::app
