// tdf: one binary, one subcommand per job. Bad input surfaces here as tdf::Error and becomes
// one line "tdf <command>: <message>" and exit code 1.
#include "commands.h"

#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/train/run_guard.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
    using namespace tdf;
    CLI::App root{"tdf: tactile-detailed textures for 3D assets (CPU re-implementation of Tactile DreamFusion)",
                  "tdf"};
    root.require_subcommand(0, 1);
    root.set_version_flag("--version", std::string("tdf ") + TDF_VERSION);
    app::GlobalOptions global;
    root.add_option("--threads", global.threads, "worker threads (0 = all cores, or SLURM_CPUS_PER_TASK)")
        ->check(CLI::NonNegativeNumber);
    root.add_flag("-q,--quiet", global.quiet, "only warnings and errors");
    root.add_flag("-v,--verbose", global.verbose, "more detail");

    std::vector<app::Command> commands = {
        app::register_render(root),  app::register_compare(root), app::register_tactile(root),
        app::register_atlas(root),   app::register_optimize(root), app::register_batch(root),
        app::register_parts(root),
    };
    for (auto& c : commands) c.app->fallthrough();  // global flags may follow the subcommand

    // `tdf help [command]`
    std::string help_topic;
    CLI::App* help = root.add_subcommand("help", "show help for tdf or one command");
    help->add_option("command", help_topic, "command name");

    try {
        root.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return root.exit(e);
    }
    if (help->parsed() || argc == 1) {
        if (help_topic.empty()) {
            std::fputs(root.help().c_str(), stdout);
            return 0;
        }
        for (auto& c : commands)
            if (c.app->get_name() == help_topic) {
                std::fputs(c.app->help().c_str(), stdout);
                return 0;
            }
        std::fprintf(stderr, "tdf help: unknown command '%s'\n", help_topic.c_str());
        return 2;
    }

    set_log_level(global.quiet ? LogLevel::Quiet : global.verbose ? LogLevel::Verbose : LogLevel::Info);
    ThreadLimit limit(global.threads);
    for (auto& c : commands) {
        if (!c.app->parsed()) continue;
        try {
            return c.run();
        } catch (const RunInterrupted& e) {
            std::fprintf(stderr, "tdf %s: %s\n", c.app->get_name().c_str(), e.what());
            return kExitInterrupted;
        } catch (const Error& e) {
            std::fprintf(stderr, "tdf %s: %s\n", c.app->get_name().c_str(), e.what());
            return 1;
        } catch (const std::bad_alloc&) {
            std::fprintf(stderr, "tdf %s: out of memory\n", c.app->get_name().c_str());
            return 1;
        } catch (const std::exception& e) {
            std::fprintf(stderr, "tdf %s: unexpected error: %s\n", c.app->get_name().c_str(), e.what());
            return 1;
        }
    }
    return 0;
}
