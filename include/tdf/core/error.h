#pragma once
/// Two error channels (see docs/robustness.md "Errors"):
///  - bad input (files, options, data) throws tdf::Error with one line naming what and where;
///    `tdf` catches it once in main, prints "tdf <command>: <message>" and exits non-zero;
///  - a broken internal invariant fails a TDF_CHECK, which prints both values and aborts.
#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace tdf {

/// An error caused by the user's input. The message is a single line that names the file,
/// key or option and says what is wrong with it.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Throws tdf::Error with a {fmt}-formatted message.
template <typename... Args>
[[noreturn]] void throw_error(fmt::format_string<Args...> format, Args&&... args) {
    throw Error(fmt::format(format, std::forward<Args>(args)...));
}

[[noreturn]] void check_failed(const char* file, int line, const std::string& what);

}  // namespace tdf

#define TDF_CHECK(cond)                                                 \
    do {                                                                \
        if (!(cond)) ::tdf::check_failed(__FILE__, __LINE__, #cond);    \
    } while (0)

#define TDF_CHECK_OP(a, op, b)                                                              \
    do {                                                                                    \
        const auto& tdf_a_ = (a);                                                           \
        const auto& tdf_b_ = (b);                                                           \
        if (!(tdf_a_ op tdf_b_))                                                            \
            ::tdf::check_failed(__FILE__, __LINE__,                                         \
                                fmt::format("{} {} {} ({} vs {})", #a, #op, #b, tdf_a_, tdf_b_)); \
    } while (0)
#define TDF_CHECK_EQ(a, b) TDF_CHECK_OP(a, ==, b)
#define TDF_CHECK_LT(a, b) TDF_CHECK_OP(a, <, b)
#define TDF_CHECK_LE(a, b) TDF_CHECK_OP(a, <=, b)
