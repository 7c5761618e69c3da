#include "rebraid/dynamic/object_bvh_update.h"

#include <algorithm>
#include <array>
#include <string>
#include <utility>

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"
#include "rebraid/top_level/bvh_stats.h"

namespace rebraid {
namespace {

constexpr std::array<std::pair<UpdateStrategy, std::string_view>, 6> kStrategyNames{{
    {UpdateStrategy::rebuild, "rebuild"},
    {UpdateStrategy::refit, "refit"},
    {UpdateStrategy::rotate, "rotate"},
    {UpdateStrategy::restructure, "restructure"},
    {UpdateStrategy::treelet, "treelet"},
    {UpdateStrategy::automatic, "auto"},
}};

/// Largest leaf of the subtree at `ref`.
std::uint32_t largest_leaf(const ObjectBvh& bvh, NodeRef ref) {
    if (ref.is_empty()) return 0;
    if (ref.is_leaf()) return ref.prim_count();
    std::uint32_t largest = 0;
    for (NodeRef child : bvh.nodes[ref.node_id()].children)
        largest = std::max(largest, largest_leaf(bvh, child));
    return largest;
}

}  // namespace

std::string_view update_strategy_name(UpdateStrategy strategy) {
    for (const auto& [value, name] : kStrategyNames)
        if (value == strategy) return name;
    return "unknown";
}

UpdateStrategy parse_update_strategy(std::string_view name) {
    std::string valid;
    for (const auto& [value, known] : kStrategyNames) {
        if (known == name) return value;
        valid += (valid.empty() ? "" : ", ") + std::string(known);
    }
    throw Error("unknown update strategy '" + std::string(name) + "' (valid: " + valid + ")");
}

void ObjectBvhUpdateSettings::validate() const {
    if (!(rebuild_sah_factor >= 1.0))
        throw Error("ObjectBvhUpdateSettings: rebuild_sah_factor " +
                    std::to_string(rebuild_sah_factor) + " is not >= 1");
    if (!(repair_sah_factor >= 1.0))
        throw Error("ObjectBvhUpdateSettings: repair_sah_factor " +
                    std::to_string(repair_sah_factor) + " is not >= 1");
    if (update_strategy_name(strategy) == "unknown")
        throw Error("ObjectBvhUpdateSettings: strategy " + std::to_string(int(strategy)) +
                    " is not an UpdateStrategy");
    if (auto_repair == UpdateStrategy::rebuild || auto_repair == UpdateStrategy::automatic ||
        update_strategy_name(auto_repair) == "unknown")
        throw Error("ObjectBvhUpdateSettings: auto_repair '" +
                    std::string(update_strategy_name(auto_repair)) +
                    "' is not one of refit, rotate, restructure, treelet");
    build.validate();
    rotation.validate();
    restructure.validate();
    treelet.validate();
}

ObjectBvhUpdater::ObjectBvhUpdater(const ObjectBvhUpdateSettings& settings) : settings_(settings) {
    settings_.validate();
}

bool ObjectBvhUpdater::uses_pre_split() const {
    const bool rotates =
        settings_.strategy == UpdateStrategy::rotate ||
        (settings_.strategy == UpdateStrategy::automatic &&
         settings_.auto_repair == UpdateStrategy::rotate) ||
        (settings_.strategy == UpdateStrategy::restructure && settings_.restructure_rotates);
    return rotates && settings_.rotation.leaf_mode == RotationLeafMode::pre_split;
}

BuildSettings ObjectBvhUpdater::rebuild_settings() const {
    BuildSettings build = settings_.build;
    if (uses_pre_split()) build.max_leaf_size = 1;
    return build;
}

double ObjectBvhUpdater::rebuild(const Mesh& mesh, ObjectBvh& bvh) {
    bvh = build_object_bvh(mesh, rebuild_settings());
    rotator_.reset();
    treelet_sampler_.reset(bvh);
    const double sah = object_bvh_sah(bvh);
    rebuild_sah_ = sah;
    return sah;
}

void ObjectBvhUpdater::apply(UpdateStrategy strategy, const Mesh& mesh, ObjectBvh& bvh,
                             ObjectBvhUpdateReport& report) {
    report.applied = strategy;
    switch (strategy) {
        case UpdateStrategy::refit:
            report.sah = refit_object_bvh(mesh, bvh, settings_.refit);
            break;
        case UpdateStrategy::rotate:
            report.rotation = rotator_.refit_and_rotate(mesh, bvh, settings_.rotation);
            report.sah = report.rotation.sah;
            break;
        case UpdateStrategy::restructure:
            if (settings_.restructure_rotates) {
                report.rotation = rotator_.refit_and_rotate(mesh, bvh, settings_.rotation);
            } else {
                refit_object_bvh(mesh, bvh, settings_.refit);
            }
            report.restructure = restructurer_.restructure(mesh, bvh, settings_.restructure);
            report.sah = report.restructure.sah;
            break;
        case UpdateStrategy::treelet:
            refit_object_bvh(mesh, bvh, settings_.refit);
            report.treelet = treelet_sampler_.optimize(mesh, bvh, settings_.treelet);
            report.sah = report.treelet.sah;
            break;
        case UpdateStrategy::rebuild:
        case UpdateStrategy::automatic:
            throw Error("ObjectBvhUpdater::apply: strategy '" +
                        std::string(update_strategy_name(strategy)) +
                        "' is not a single pass (internal error)");
    }
}

ObjectBvhUpdateReport ObjectBvhUpdater::update(const Mesh& mesh, ObjectBvh& bvh) {
    const BuildTimer timer;
    check_mesh_matches(mesh, bvh, "ObjectBvhUpdater::update");
    ObjectBvhUpdateReport report;
    UpdateStrategy strategy = settings_.strategy;
    if (!rebuild_sah_) {
        // The first tree seen counts as the last rebuild; rotations in pre_split mode need
        // one triangle per leaf, so another tree is rebuilt once, now.
        rebuild_sah_ = object_bvh_sah(bvh);
        treelet_sampler_.reset(bvh);
        if (uses_pre_split() && largest_leaf(bvh, bvh.root) > 1) strategy = UpdateStrategy::rebuild;
    }
    if (strategy == UpdateStrategy::automatic && last_sah_ && previous_sah_) {
        // Rebuild straight away when the SAH's trend says this frame passes the factor:
        // the refit or repair pass would be wasted work.
        const double predicted = *last_sah_ + (*last_sah_ - *previous_sah_);
        if (predicted > settings_.rebuild_sah_factor * *rebuild_sah_)
            strategy = UpdateStrategy::rebuild;
    }
    if (strategy == UpdateStrategy::rebuild) {
        report.sah = rebuild(mesh, bvh);
        report.applied = UpdateStrategy::rebuild;
    } else if (strategy != UpdateStrategy::automatic) {
        apply(strategy, mesh, bvh, report);
    } else {
        // auto: refit while that keeps the SAH within repair_sah_factor of the last rebuild,
        // repair past it, rebuild past rebuild_sah_factor. Rotations replace the refit (they
        // refit in the same pass), so whether they run is decided by the previous frame's
        // SAH; the other repairs follow the refit and are decided by this frame's.
        const double repair_above = settings_.repair_sah_factor * *rebuild_sah_;
        const UpdateStrategy repair = settings_.auto_repair;
        if (repair == UpdateStrategy::rotate) {
            apply(last_sah_ && *last_sah_ > repair_above ? repair : UpdateStrategy::refit, mesh,
                  bvh, report);
        } else {
            apply(UpdateStrategy::refit, mesh, bvh, report);
            if (report.sah > repair_above && repair != UpdateStrategy::refit &&
                report.sah <= settings_.rebuild_sah_factor * *rebuild_sah_) {
                if (repair == UpdateStrategy::restructure) {
                    report.restructure =
                        restructurer_.restructure(mesh, bvh, settings_.restructure);
                    report.sah = report.restructure.sah;
                } else {
                    report.treelet = treelet_sampler_.optimize(mesh, bvh, settings_.treelet);
                    report.sah = report.treelet.sah;
                }
                report.applied = repair;
            }
        }
        if (report.sah > settings_.rebuild_sah_factor * *rebuild_sah_) {
            report.sah = rebuild(mesh, bvh);
            report.applied = UpdateStrategy::rebuild;
        }
    }
    // After a rebuild the trend starts afresh.
    previous_sah_ = report.applied == UpdateStrategy::rebuild ? std::nullopt : last_sah_;
    last_sah_ = report.sah;
    report.sah_over_rebuild = *rebuild_sah_ > 0.0 ? report.sah / *rebuild_sah_ : 1.0;
    report.update_ms = timer.elapsed_ms();
    return report;
}

}  // namespace rebraid
