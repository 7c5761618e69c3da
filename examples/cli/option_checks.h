#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace rebraid::cli {

// CLI11 checks whose messages say, in the user's words, what the value should be. CLI11's own
// (CLI::Range, CLI::NonNegativeNumber, CLI::CheckedTransformer) print "not in range" for text
// that is no number, bounds of 309 digits, and enum maps as "{a->0,b->1} OR {0,1}". Each runs
// before CLI11 converts the text, and prints nothing in --help beyond the option's own text.

/// A whole number from `min` to `max`: "-5" for a count says "must be at least 1".
CLI::Validator whole_number(std::int64_t min, std::int64_t max);

/// A finite number of at least `min`.
CLI::Validator number_at_least(double min);

/// A finite number from `min` to `max`.
CLI::Validator number_between(double min, double max);

/// A finite number (times and seconds, which may be negative).
CLI::Validator finite_number();

/// One of `names` (exact spelling); the message lists them.
CLI::Validator one_of(std::vector<std::string> names);

/// "a, b, c": names for help texts and messages.
std::string join_names(const std::vector<std::string>& names);

/// For an enum option: one of the names of `choices`, replaced by its enum's number, which
/// CLI11 then converts to the enum. The message lists the names.
template <class Enum>
CLI::Validator named_value(const std::map<std::string, Enum>& choices) {
    std::vector<std::string> names;
    for (const auto& [name, value] : choices) names.push_back(name);
    return CLI::Validator(
        [choices, names](std::string& text) -> std::string {
            const auto found = choices.find(text);
            if (found == choices.end()) return "'" + text + "' is not one of: " + join_names(names);
            text = std::to_string(static_cast<long long>(found->second));
            return {};
        },
        "");
}

}  // namespace rebraid::cli
