// Checks of option values shared by the subcommands (commands.hpp).
#include <charconv>
#include <cmath>
#include <string>

#include "commands.hpp"

namespace cisamr::app {
namespace {

std::string number_text(double value) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  return std::string(buffer, end);
}

// The value as typed, short and on one line, for the message.
std::string as_typed(const std::string& text) {
  std::string shown;
  for (char c : text.substr(0, 24)) shown += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
  return text.size() > 24 ? shown + "..." : shown;
}

}  // namespace

CLI::Validator number_in(double lo, double hi, bool whole) {
  const std::string range = "[" + number_text(lo) + ", " + number_text(hi) + "]";
  const std::string wanted = std::string(whole ? "must be a whole number in " : "must be a number in ") + range;
  return CLI::Validator(
      [=](std::string& text) {
        double value = 0;
        const char* first = text.data();
        const char* last = first + text.size();
        if (!text.empty() && *first == '+') ++first;
        const auto [end, ec] = std::from_chars(first, last, value);
        const bool valid = ec == std::errc() && end == last && std::isfinite(value) && value >= lo && value <= hi &&
                           (!whole || value == std::floor(value));
        return valid ? std::string() : wanted + " (got " + as_typed(text) + ")";
      },
      range);
}

CLI::Validator named(const std::string& option, CLI::Validator check) {
  return CLI::Validator(
      [option, check](std::string& text) {
        const std::string message = check(text);
        return message.empty() ? message : option + ": " + message;
      },
      check.get_description());
}

CLI::Validator output_path() {
  return CLI::Validator([](std::string& text) { return text.empty() ? std::string("an empty path: name a file (or - for standard output)") : std::string(); },
                        "");
}

}  // namespace cisamr::app
