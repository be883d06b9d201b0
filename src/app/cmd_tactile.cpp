// Placeholder until `tdf tactile` lands.
#include "commands.h"

#include <cstdio>

namespace tdf::app {

Command register_tactile(CLI::App& root) {
    Command command;
    command.app = root.add_subcommand("tactile", "(not implemented yet)");
    command.run = [] {
        std::fprintf(stderr, "tdf tactile: not implemented yet\n");
        return 2;
    };
    return command;
}

}  // namespace tdf::app
