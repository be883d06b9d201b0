// Placeholder until `tdf atlas` lands.
#include "commands.h"

#include <cstdio>

namespace tdf::app {

Command register_atlas(CLI::App& root) {
    Command command;
    command.app = root.add_subcommand("atlas", "(not implemented yet)");
    command.run = [] {
        std::fprintf(stderr, "tdf atlas: not implemented yet\n");
        return 2;
    };
    return command;
}

}  // namespace tdf::app
