// Placeholder until `tdf compare` lands.
#include "commands.h"

#include <cstdio>

namespace tdf::app {

Command register_compare(CLI::App& root) {
    Command command;
    command.app = root.add_subcommand("compare", "(not implemented yet)");
    command.run = [] {
        std::fprintf(stderr, "tdf compare: not implemented yet\n");
        return 2;
    };
    return command;
}

}  // namespace tdf::app
