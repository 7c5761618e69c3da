#include "stats_json.h"

#include <string>

namespace rebraid::cli {

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
