#include "option_checks.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <utility>

namespace rebraid::cli {

namespace {

/// `text` as a finite number, or nothing when it is not one (trailing text included).
std::optional<double> parse_number(const std::string& text) {
    if (text.empty()) return std::nullopt;
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (end != text.c_str() + text.size() || !std::isfinite(value)) return std::nullopt;
    return value;
}

/// Numbers as people write them: 0.5, 1e+06, never 0.500000.
std::string format_number(double value) {
    std::ostringstream out;
    out << value;
    return out.str();
}

}  // namespace

CLI::Validator whole_number(std::int64_t min, std::int64_t max) {
    return CLI::Validator(
        [min, max](std::string& text) -> std::string {
            std::int64_t value = 0;
            const char* end = text.data() + text.size();
            const auto [parsed_end, error] = std::from_chars(text.data(), end, value);
            const std::string range = std::to_string(min) + " to " + std::to_string(max);
            if (error == std::errc::result_out_of_range)
                return "'" + text + "' is too large: it must be a whole number from " + range;
            if (error != std::errc() || parsed_end != end || text.empty())
                return "'" + text + "' is not a whole number (from " + range + ")";
            if (value < min || value > max)
                return std::to_string(value) + " is out of range: it must be from " + range;
            return {};
        },
        "");
}

CLI::Validator number_at_least(double min) {
    return CLI::Validator(
        [min](std::string& text) -> std::string {
            const std::optional<double> value = parse_number(text);
            if (!value) return "'" + text + "' is not a number";
            if (*value < min)
                return text + " is too small: it must be at least " + format_number(min);
            return {};
        },
        "");
}

CLI::Validator number_between(double min, double max) {
    return CLI::Validator(
        [min, max](std::string& text) -> std::string {
            const std::optional<double> value = parse_number(text);
            if (!value) return "'" + text + "' is not a number";
            if (*value < min || *value > max)
                return text + " is out of range: it must be from " + format_number(min) + " to " +
                       format_number(max);
            return {};
        },
        "");
}

CLI::Validator finite_number() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            if (!parse_number(text)) return "'" + text + "' is not a finite number";
            return {};
        },
        "");
}

CLI::Validator one_of(std::vector<std::string> names) {
    return CLI::Validator(
        [names = std::move(names)](std::string& text) -> std::string {
            for (const std::string& name : names)
                if (name == text) return {};
            return "'" + text + "' is not one of: " + join_names(names);
        },
        "");
}

std::string join_names(const std::vector<std::string>& names) {
    std::string joined;
    for (const std::string& name : names) joined += (joined.empty() ? "" : ", ") + name;
    return joined;
}

}  // namespace rebraid::cli
