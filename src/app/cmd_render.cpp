// Placeholder until `tdf render` lands.
#include "commands.h"

#include <cstdio>

namespace tdf::app {

Command register_render(CLI::App& root) {
    Command command;
    command.app = root.add_subcommand("render", "(not implemented yet)");
    command.run = [] {
        std::fprintf(stderr, "tdf render: not implemented yet\n");
        return 2;
    };
    return command;
}

}  // namespace tdf::app
