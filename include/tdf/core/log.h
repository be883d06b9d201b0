#pragma once
/// Console messages. Everything goes to stderr so stdout stays free for machine-readable output
/// (`tdf compare --json`, reports). `--quiet` silences info; warnings and errors always print.
#include <fmt/format.h>

#include <string>

namespace tdf {

enum class LogLevel { Quiet = 0, Info = 1, Verbose = 2 };

void set_log_level(LogLevel level);
LogLevel log_level();
void log_line(const char* prefix, const std::string& message);

template <typename... Args>
void log_info(fmt::format_string<Args...> format, Args&&... args) {
    if (log_level() >= LogLevel::Info)
        log_line("", fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void log_verbose(fmt::format_string<Args...> format, Args&&... args) {
    if (log_level() >= LogLevel::Verbose)
        log_line("", fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void log_warning(fmt::format_string<Args...> format, Args&&... args) {
    log_line("warning: ", fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace tdf
