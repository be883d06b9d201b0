// Placeholder until `tdf optimize` lands.
#include "commands.h"

#include <cstdio>

namespace tdf::app {

Command register_optimize(CLI::App& root) {
    Command command;
    command.app = root.add_subcommand("optimize", "(not implemented yet)");
    command.run = [] {
        std::fprintf(stderr, "tdf optimize: not implemented yet\n");
        return 2;
    };
    return command;
}

}  // namespace tdf::app
