// tdf: one binary, one subcommand per job. Bad input surfaces here as tdf::Error and becomes
// one line "tdf <command>: <message>" and exit code 1; usage errors (unknown option, missing
// argument, value out of range or not finite) are one line and exit code 1 as well. Running
// out of memory (kExitOutOfMemory) and any other exception (kExitUnexpected) have codes of their
// own, so that `tdf batch` retries those and not bad input (docs/commands/batch.md).
#include <tdf/core/error.h>
#include <tdf/core/exit_codes.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/train/run_guard.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <regex>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "commands.h"

namespace {

// A refinement iteration allocates and frees dozens of 1-12 MB images (guidance requests, blurs,
// views). glibc maps each block over its dynamic threshold afresh, so every iteration paid for
// their pages again in faults and kernel zeroing: 480k page faults and 15 % of the main job's
// time. Blocks up to 32 MB (glibc's largest threshold) now come from the heap and are reused;
// the multi-GB maps of a 4096^2 run are still mapped and returned when freed. Outputs are
// unchanged (docs/measurements.md, "The main job by stage").
// One arena: TBB's worker threads otherwise allocate from an arena of their own, whose freed
// blocks the main thread never reuses; with patches and views of different sizes the two heaps
// fragmented, 569 -> 591 MB peak in the main job (and 2 % slower), 2026-12-06.
void keep_freed_blocks_for_reuse() {
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 64 << 20);
    mallopt(M_ARENA_MAX, 1);
#endif
}

// CLI11 renders a negated flag with its default flag value ("--no-tileable{false}"); the value
// is an implementation detail of `!--no-tileable`, so the help shows the bare name.
class HelpFormatter : public CLI::Formatter {
public:
    std::string make_option_name(const CLI::Option* opt, bool is_positional) const override {
        std::string name = CLI::Formatter::make_option_name(opt, is_positional);
        return std::regex_replace(name, std::regex("\\{[^}]*\\}"), "");
    }
};

// "tdf tactile convert": the chain of selected subcommands (as far as parsing got).
std::string command_path(const CLI::App& root) {
    std::string path;
    const CLI::App* app = &root;
    while (true) {
        const auto selected = app->get_subcommands();
        if (selected.empty()) break;
        app = selected.front();
        path += (path.empty() ? "" : " ") + app->get_name();
    }
    return path;
}

// CLI11 prints doubles with %f, so 1e400 against DBL_MAX quotes a 309-digit number; long
// digit runs are rewritten in scientific notation.
std::string shorten_numbers(const std::string& message) {
    static const std::regex long_number("[0-9]{16,}(\\.[0-9]+)?");
    std::string out;
    auto begin = std::sregex_iterator(message.begin(), message.end(), long_number);
    std::size_t last = 0;
    for (auto it = begin; it != std::sregex_iterator(); ++it) {
        out += message.substr(last, std::size_t(it->position()) - last);
        out += fmt::format("{:.3g}", std::strtod(it->str().c_str(), nullptr));
        last = std::size_t(it->position() + it->length());
    }
    return out + message.substr(last);
}

// CLI11's NonNegativeNumber/PositiveNumber validators let NaN through (NaN <= 0 is false), and
// ranges accept infinities. A floating-point option must be finite unless its own default is
// not (`compare --hardfail` defaults to inf). Throws tdf::Error naming the option.
void check_finite_options(const CLI::App& app) {
    for (const CLI::Option* option : app.get_options()) {
        if (option->count() == 0) continue;
        const std::string type = option->get_type_name();
        if (type.find("FLOAT") == std::string::npos && type.find("NUMBER") == std::string::npos) continue;
        const std::string& fallback = option->get_default_str();
        const bool default_finite = fallback.empty() || std::isfinite(std::strtod(fallback.c_str(), nullptr));
        for (const std::string& text : option->results()) {
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (end == text.c_str() || *end != '\0') continue;  // CLI11 reports non-numbers itself
            if (std::isnan(value) || (std::isinf(value) && default_finite))
                tdf::throw_error("{}: must be a finite number, got {}", option->get_name(), text);
        }
    }
    for (const CLI::App* sub : app.get_subcommands()) check_finite_options(*sub);
}

// The parsed command's positional arguments (its input files), for messages that have no
// file of their own.
std::string positional_arguments(const CLI::App& app) {
    std::string out;
    for (const CLI::Option* option : app.get_options())
        if (option->get_positional() && option->count() > 0)
            for (const std::string& r : option->results()) out += (out.empty() ? "'" : ", '") + r + "'";
    for (const CLI::App* sub : app.get_subcommands()) {
        const std::string more = positional_arguments(*sub);
        if (!more.empty()) out += (out.empty() ? "" : ", ") + more;
    }
    return out;
}

// Test-only (tests/batch/batch_retry_test.sh, bench/batch_1000.sh): TDF_TEST_KILL_JOBS is a
// comma-separated list of `name[:N]`; the batch job `name` (TDF_BATCH_JOB, set by `tdf batch`)
// kills itself with SIGKILL on its attempts 1 to N (TDF_BATCH_ATTEMPT; N defaults to 1), as the
// OOM killer would. Deterministic, unlike racing a kill from outside.
void kill_self_if_test_victim() {
    const char* victims = std::getenv("TDF_TEST_KILL_JOBS");
    const char* job = std::getenv("TDF_BATCH_JOB");
    const char* attempt = std::getenv("TDF_BATCH_ATTEMPT");
    if (!victims || !job || !attempt) return;
    const std::string list = std::string(",") + victims + ",";
    const std::string name = job;
    for (std::size_t at = 0; (at = list.find("," + name, at)) != std::string::npos; ++at) {
        const std::size_t end = at + 1 + name.size();
        if (list[end] != ',' && list[end] != ':') continue;
        const int last_attempt = list[end] == ':' ? std::atoi(list.c_str() + end + 1) : 1;
        if (std::atoi(attempt) <= last_attempt) std::raise(SIGKILL);
    }
}

}  // namespace

int main(int argc, char** argv) {
    using namespace tdf;
    keep_freed_blocks_for_reuse();
    CLI::App root{"tdf: tactile-detailed textures for 3D assets (CPU re-implementation of Tactile DreamFusion)",
                  "tdf"};
    root.formatter(std::make_shared<HelpFormatter>());  // before the subcommands, which inherit it
    root.require_subcommand(0, 1);
    root.set_version_flag("--version", std::string("tdf ") + TDF_VERSION);
    app::GlobalOptions global;
    root.add_option("--threads", global.threads, "worker threads (0 = all cores, or SLURM_CPUS_PER_TASK)")
        ->check(CLI::Range(0, 4096));
    root.add_flag("-q,--quiet", global.quiet, "only warnings and errors");
    root.add_flag("-v,--verbose", global.verbose, "more detail");

    std::vector<app::Command> commands = {
        app::register_render(root),  app::register_compare(root), app::register_tactile(root),
        app::register_atlas(root),   app::register_optimize(root), app::register_batch(root),
        app::register_parts(root),
    };
    for (auto& c : commands) c.app->fallthrough();  // global flags may follow the subcommand

    // `tdf help [command [sub-command]]`
    std::vector<std::string> help_topic;
    CLI::App* help = root.add_subcommand("help", "show the commands, or every option of one command");
    help->add_option("command", help_topic, "command and sub-command, e.g. `tdf help tactile convert`");

    try {
        root.parse(argc, argv);
        check_finite_options(root);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return root.exit(e);  // --help, --version
        const std::string path = command_path(root);
        const std::string command = path.substr(0, path.find(' '));
        std::string message = shorten_numbers(e.what());
        std::replace(message.begin(), message.end(), '\n', ' ');
        std::fprintf(stderr,
                     "tdf%s%s: %s (see `tdf help%s%s`)\n",
                     command.empty() ? "" : " ",
                     command.c_str(),
                     message.c_str(),
                     path.empty() ? "" : " ",
                     path.c_str());
        return 1;
    } catch (const Error& e) {
        const std::string path = command_path(root);
        std::fprintf(stderr,
                     "tdf%s%s: %s\n",
                     path.empty() ? "" : " ",
                     path.substr(0, path.find(' ')).c_str(),
                     e.what());
        return 1;
    }
    if (help->parsed() || argc == 1) {
        // Format directly: App::help() would show the selected `help` subcommand's own page.
        const CLI::App* topic = &root;
        std::string name = "tdf";
        for (const std::string& word : help_topic) {
            const auto found =
                topic->get_subcommands([&](const CLI::App* sub) { return sub->get_name() == word; });
            if (found.empty()) {
                std::fprintf(stderr,
                             "tdf help: '%s' has no command '%s' (see `tdf help%s`)\n",
                             name.c_str(),
                             word.c_str(),
                             name == "tdf" ? "" : (" " + name.substr(4)).c_str());
                return 1;
            }
            topic = found.front();
            name += " " + word;
        }
        std::fputs(topic->get_formatter()->make_help(topic, name, CLI::AppFormatMode::Normal).c_str(),
                   stdout);
        return 0;
    }

    set_log_level(global.quiet ? LogLevel::Quiet : global.verbose ? LogLevel::Verbose : LogLevel::Info);
    ThreadLimit limit(global.threads);
    kill_self_if_test_victim();
    for (auto& c : commands) {
        if (!c.app->parsed()) continue;
        const std::string name = c.app->get_name();
        try {
            return c.run();
        } catch (const RunInterrupted& e) {
            std::fprintf(stderr, "tdf %s: %s\n", c.app->get_name().c_str(), e.what());
            return kExitInterrupted;
        } catch (const Error& e) {
            std::fprintf(stderr, "tdf %s: %s\n", name.c_str(), e.what());
            return 1;
        } catch (const std::bad_alloc&) {
            // Loaders check sizes before allocating; reaching this means the inputs together
            // need more memory than the machine has.
            const std::string inputs = positional_arguments(*c.app);
            std::fprintf(stderr,
                         "tdf %s: out of memory while processing %s (the inputs or options need more "
                         "memory than is available)\n",
                         name.c_str(),
                         inputs.empty() ? "the command" : inputs.c_str());
            return kExitOutOfMemory;
        } catch (const std::exception& e) {
            std::fprintf(stderr, "tdf %s: unexpected error: %s\n", name.c_str(), e.what());
            return kExitUnexpected;
        }
    }
    return 0;
}
