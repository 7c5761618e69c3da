#include "stats_json.h"

#include <sys/resource.h>

#include <string>

namespace rebraid::cli {

std::uint64_t peak_rss_bytes() {
    rusage usage{};
    if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
    return std::uint64_t(usage.ru_maxrss) * 1024u;
}

nlohmann::ordered_json stats_to_json(const AccelStats& stats) {
    nlohmann::ordered_json json = nlohmann::ordered_json::object();
    for_each_stats_field(stats, [&](std::string_view key, const auto& value) {
        if constexpr (IsOptional<std::decay_t<decltype(value)>>::value) {
            if (value) json[std::string(key)] = *value;
        } else {
            json[std::string(key)] = value;
        }
    });
    return json;
}

}  // namespace rebraid::cli
