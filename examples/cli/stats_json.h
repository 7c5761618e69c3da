#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>
#include <type_traits>

#include "rebraid/core/accel.h"

namespace rebraid::cli {

/// Calls `visit(key, value)` for every AccelStats field, keys named as the struct's fields.
/// Optional fields are passed as std::optional; a new field of AccelStats is one line here.
template <class Visitor>
void for_each_stats_field(const AccelStats& stats, Visitor&& visit) {
    visit("triangles", stats.triangles);
    visit("instances", stats.instances);
    visit("meshes", stats.meshes);
    visit("build_ms", stats.build_ms);
    visit("top_build_ms", stats.top_build_ms);
    visit("sah", stats.sah);
    visit("nodes", stats.nodes);
    visit("leaves", stats.leaves);
    visit("memory_bytes", stats.memory_bytes);
    visit("structure_hash", stats.structure_hash);
    visit("brefs", stats.brefs);
    visit("budget", stats.budget);
    visit("opened", stats.opened);
    visit("mesh_copies", stats.mesh_copies);
    visit("kernels", stats.kernels);
    visit("triangle_test", stats.triangle_test);
}

template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};

/// Peak resident memory of this process so far, in bytes (getrusage's ru_maxrss, which Linux
/// reports in KiB). `rebraid stats` reads it after the build, so it covers loading the scene
/// and building the structure.
std::uint64_t peak_rss_bytes();

/// One JSON member per AccelStats field, in declaration order; empty optional fields are
/// left out.
nlohmann::ordered_json stats_to_json(const AccelStats& stats);

}  // namespace rebraid::cli
