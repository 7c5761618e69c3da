#include "rebraid/io/ray_file.h"

#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <ostream>
#include <string_view>
#include <system_error>

#include "rebraid/core/error.h"

namespace rebraid {
namespace {

constexpr int kRayFieldCount = 8;
constexpr std::array<const char*, kRayFieldCount> kRayFieldNames = {"ox", "oy", "oz",    "dx",
                                                                    "dy", "dz", "tnear", "tfar"};

bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/// Builds the message prefix every bad-line error shares.
std::string line_error(const std::string& source_name, std::size_t line_number,
                       const std::string& what) {
    return "ray file '" + source_name + "': line " + std::to_string(line_number) + ": " + what;
}

/// Parses one whole field as a float. Returns false when the text is not a float or is
/// beyond float range. Locale-independent (from_chars), so '.' is always the decimal point.
bool parse_float(std::string_view text, float& value) {
    // from_chars rejects a leading '+', which printf-style writers and people both produce.
    if (text.size() > 1 && text.front() == '+' && text[1] != '-' && text[1] != '+')
        text.remove_prefix(1);
    const char* const first = text.data();
    const char* const last = text.data() + text.size();
    float parsed = 0.0f;
    const auto [end, error] = std::from_chars(first, last, parsed, std::chars_format::general);
    if (end != last) return false;
    if (error == std::errc()) {
        value = parsed;
        return true;
    }
    if (error != std::errc::result_out_of_range) return false;
    // Out of range is either overflow (a real error) or underflow (tiny values, which become
    // the nearest float). The double parse tells them apart.
    double wide = 0.0;
    const auto [wide_end, wide_error] =
        std::from_chars(first, last, wide, std::chars_format::general);
    if (wide_end != last || wide_error != std::errc()) return false;
    if (std::fabs(wide) > static_cast<double>(std::numeric_limits<float>::max())) return false;
    value = static_cast<float>(wide);
    return true;
}

/// Splits `line` into whitespace-separated fields; returns how many there were (it stops
/// storing after `fields.size()` but keeps counting, so the error can say how many it saw).
std::size_t split_fields(std::string_view line,
                         std::array<std::string_view, kRayFieldCount>& fields) {
    std::size_t count = 0;
    std::size_t pos = 0;
    while (pos < line.size()) {
        while (pos < line.size() && is_space(line[pos])) ++pos;
        if (pos == line.size()) break;
        const std::size_t start = pos;
        while (pos < line.size() && !is_space(line[pos])) ++pos;
        if (count < fields.size()) fields[count] = line.substr(start, pos - start);
        ++count;
    }
    return count;
}

/// Converts one data line into a ray, checking every rule listed in ray_file.h.
Ray parse_ray_line(std::string_view line, const std::string& source_name, std::size_t line_number) {
    std::array<std::string_view, kRayFieldCount> fields;
    const std::size_t field_count = split_fields(line, fields);
    if (field_count != kRayFieldCount)
        throw Error(line_error(source_name, line_number,
                               "expected 8 fields 'ox oy oz dx dy dz tnear tfar', found " +
                                   std::to_string(field_count)));

    std::array<float, kRayFieldCount> values{};
    for (int i = 0; i < kRayFieldCount; ++i) {
        const std::string text(fields[i]);
        if (!parse_float(fields[i], values[i]))
            throw Error(
                line_error(source_name, line_number,
                           std::string(kRayFieldNames[i]) + " '" + text + "' is not a float"));
        if (std::isnan(values[i]))
            throw Error(
                line_error(source_name, line_number, std::string(kRayFieldNames[i]) + " is NaN"));
        // Origin and direction must be finite; only tfar may be infinite (an open segment).
        const bool is_tfar = i == kRayFieldCount - 1;
        if (!is_tfar && std::isinf(values[i]))
            throw Error(
                line_error(source_name, line_number,
                           std::string(kRayFieldNames[i]) + " '" + text + "' is not finite"));
    }

    Ray ray;
    ray.org = {values[0], values[1], values[2]};
    ray.dir = {values[3], values[4], values[5]};
    ray.tnear = values[6];
    ray.tfar = values[7];
    if (ray.dir.x == 0.0f && ray.dir.y == 0.0f && ray.dir.z == 0.0f)
        throw Error(line_error(source_name, line_number, "direction is zero"));
    if (ray.tnear < 0.0f)
        throw Error(line_error(source_name, line_number,
                               "tnear " + std::string(fields[6]) + " is negative"));
    if (ray.tfar == -std::numeric_limits<float>::infinity())
        throw Error(line_error(source_name, line_number, "tfar is -inf"));
    return ray;
}

/// Appends `value` as `%.9g` would print it, without depending on the C locale.
void append_float(std::string& out, float value) {
    std::array<char, 32> buffer;
    const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value,
                                      std::chars_format::general, 9);
    out.append(buffer.data(), result.ptr);
}

}  // namespace

std::vector<Ray> read_rays(std::istream& in, const std::string& source_name) {
    std::vector<Ray> rays;
    std::string line;
    std::size_t line_number = 0;
    while (std::getline(in, line)) {
        ++line_number;
        std::size_t first = 0;
        while (first < line.size() && is_space(line[first])) ++first;
        if (first == line.size() || line[first] == '#') continue;
        rays.push_back(parse_ray_line(line, source_name, line_number));
    }
    if (in.bad())
        throw Error("ray file '" + source_name + "': reading failed after line " +
                    std::to_string(line_number) + ": " + std::strerror(errno));
    return rays;
}

std::vector<Ray> read_ray_file(const std::string& path) {
    std::error_code error;
    if (std::filesystem::is_directory(path, error))
        throw Error("ray file '" + path + "' is a directory, not a file");
    errno = 0;
    std::ifstream file(path);
    if (!file)
        throw Error("cannot open ray file '" + path +
                    "': " + (errno != 0 ? std::strerror(errno) : "unknown reason"));
    return read_rays(file, path);
}

void write_rays(std::ostream& out, std::span<const Ray> rays) {
    std::string line;
    for (const Ray& ray : rays) {
        line.clear();
        const float values[kRayFieldCount] = {ray.org.x, ray.org.y, ray.org.z, ray.dir.x,
                                              ray.dir.y, ray.dir.z, ray.tnear, ray.tfar};
        for (int i = 0; i < kRayFieldCount; ++i) {
            if (i > 0) line += ' ';
            append_float(line, values[i]);
        }
        line += '\n';
        out << line;
    }
}

void write_hits(std::ostream& out, std::span<const Hit> hits) {
    std::string line;
    for (const Hit& hit : hits) {
        line.clear();
        if (hit.is_hit()) {
            append_float(line, hit.t);
            line += ' ';
            line += std::to_string(hit.instance_id);
            line += ' ';
            line += std::to_string(hit.prim_id);
        } else {
            line = "inf -1 -1";
        }
        line += '\n';
        out << line;
    }
}

}  // namespace rebraid
