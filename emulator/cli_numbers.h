// Numeric command-line options of mocosim and mococheck, read strictly (and
// file options that refuse an empty path): the
// whole argument must be one finite number within the option's range, or the
// parse fails (a usage error, exit 2) with a message naming the option and the
// range. CLI11's own conversions let "-1" and "1e23" become 2^64-1 for an
// unsigned option and "nan" pass a range check.
#ifndef MOCO_CLI_NUMBERS_H_
#define MOCO_CLI_NUMBERS_H_

#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>

#include <CLI/CLI.hpp>

namespace moco::cli {

// `text` as a T: integers are decimal digits (a leading '-' only for signed
// types), floating point is a finite decimal number ("1.5", "2e3"); nothing
// may precede or follow. nullopt when the text is not such a number or does
// not fit in T.
template <class T>
std::optional<T> ParseNumber(std::string_view text) {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>);
  if (text.empty()) return std::nullopt;
  T value{};
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if constexpr (std::is_floating_point_v<T>) {
    const auto [ptr, ec] = std::from_chars(first, last, value, std::chars_format::general);
    if (ec != std::errc() || ptr != last || !std::isfinite(value)) return std::nullopt;
  } else {
    const auto [ptr, ec] = std::from_chars(first, last, value, 10);
    if (ec != std::errc() || ptr != last) return std::nullopt;
  }
  return value;
}

// "0..18446744073709551615", "0..86400".
template <class T>
std::string RangeText(T min, T max) {
  std::ostringstream s;
  if constexpr (std::is_floating_point_v<T>) {
    s << min << ".." << max;
  } else if constexpr (sizeof(T) == 1) {
    s << static_cast<int>(min) << ".." << static_cast<int>(max);
  } else {
    s << min << ".." << max;
  }
  return s.str();
}

// Why `text` is not acceptable for an option taking a T in [min, max]
// ("" when it is); the value goes to `out` when it is.
template <class T>
std::string CheckNumber(std::string_view text, T min, T max, T& out) {
  const std::optional<T> v = ParseNumber<T>(text);
  const char* what = std::is_floating_point_v<T> ? "a finite number" : "a whole number";
  if (!v || *v < min || *v > max) {
    return "\"" + std::string(text) + "\" is not " + what + " in " + RangeText(min, max);
  }
  out = *v;
  return "";
}

// Adds option `name` storing into `value` (whose current value is the
// default) only a number in [min, max]; anything else fails the parse with a
// CLI::ValidationError naming the option and the range.
// REQUIRES: `value` outlives the parse.
template <class T>
CLI::Option* AddNumber(CLI::App* app, const std::string& name, T& value, T min, T max,
                       const std::string& description) {
  std::ostringstream def;
  if constexpr (sizeof(T) == 1) {
    def << static_cast<int>(value);
  } else {
    def << value;
  }
  CLI::Option* opt = app->add_option_function<std::string>(
      name,
      [&value, name, min, max](const std::string& text) {
        if (std::string err = CheckNumber(text, min, max, value); !err.empty()) {
          throw CLI::ValidationError(name, err);
        }
      },
      description + " [" + RangeText(min, max) + "]");
  opt->type_name(std::is_floating_point_v<T> ? "NUMBER" : "INT");
  opt->default_str(def.str());
  return opt;
}

// Parses the command line. Every parse error (an unknown option, a missing or
// unreadable file, a number out of range) is a usage error: the message is
// printed and `usage_exit` returned; --help and --version print and return 0.
// nullopt: parsed, go on.
inline std::optional<int> ParseCommandLine(CLI::App& app, int argc, char** argv,
                                           int usage_exit = 2) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return usage_exit;
  }
  return std::nullopt;
}

// A file option given an empty value (`--json ""`, often an unset shell
// variable) would silently mean "not given": refuse it as a usage error.
inline CLI::Validator NonEmptyPath() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        return value.empty() ? "needs a path; an empty one is not a file (leave the option out "
                               "to write nothing)"
                             : "";
      },
      "", "NonEmptyPath");
}

}  // namespace moco::cli

#endif  // MOCO_CLI_NUMBERS_H_
