#pragma once

// Comparing the answers of two structures on the same rays, with the tolerance the project
// promises: same closest-hit t within 1e-4 relative, same instance and primitive ids
// (unless two triangles are hit at the same t: a tie either may win), same occlusion.

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "rebraid/core/accel.h"
#include "rebraid/core/bbox.h"

namespace rebraid::test {

struct AccelAnswers {
    std::vector<Hit> hits;
    std::vector<char> occluded;
};

inline AccelAnswers trace_all(const Accel& accel, const std::vector<Ray>& rays) {
    AccelAnswers answers{std::vector<Hit>(rays.size()), std::vector<char>(rays.size())};
    tbb::parallel_for(std::size_t(0), rays.size(), [&](std::size_t i) {
        answers.hits[i] = accel.intersect(rays[i]);
        answers.occluded[i] = accel.occluded(rays[i]);
    });
    return answers;
}

/// Tolerances of a comparison between two structures on one scene.
struct Tolerance {
    /// Largest |coordinate| of the scene: world-space vertices of a flattened scene are
    /// rounded at this magnitude, so t can differ by a few ulps of it whatever t is.
    float scene_magnitude = 1.0f;
    /// Barycentric distance to an edge under which a ray grazes the edge: there, whether a
    /// silhouette edge is hit depends on how the vertices were rounded (world-space copies in
    /// a flat structure, object-space originals behind a transform in an instanced one).
    float edge_graze = 1e-4f;
    /// Largest fraction of rays allowed to differ at a grazed edge.
    double max_graze_fraction = 1e-3;
};

inline Tolerance tolerance_for(const BBox3f& bounds) {
    const Vec3f m = max(max(bounds.min, -bounds.min), max(bounds.max, -bounds.max));
    return {std::max({m.x, m.y, m.z, 1e-30f})};
}

/// Same t: within 1e-4 relative, or within 64 ulps of the scene's magnitude (rays from the
/// generators have unit directions, so t is a world distance).
inline bool same_t(float a, float b, const Tolerance& tolerance) {
    if (std::isinf(a) || std::isinf(b)) return a == b;
    const float absolute = tolerance.scene_magnitude * 0x1.0p-18f;
    return std::fabs(a - b) <= 1e-4f * std::max(std::fabs(a), std::fabs(b)) + absolute;
}

inline bool grazes_edge(const Hit& hit, const Tolerance& tolerance) {
    return hit.is_hit() && std::min({hit.u, hit.v, 1.0f - hit.u - hit.v}) < tolerance.edge_graze;
}

/// Asserts every ray agrees, but for rare disagreements at grazed edges; reports the first
/// few disagreements with their ray index.
inline void expect_same_answers(const AccelAnswers& expected, const AccelAnswers& actual,
                                const Tolerance& tolerance) {
    ASSERT_EQ(expected.hits.size(), actual.hits.size());
    std::size_t mismatches = 0, grazes = 0, hits = 0;
    for (std::size_t i = 0; i < expected.hits.size(); ++i) {
        const Hit& e = expected.hits[i];
        const Hit& a = actual.hits[i];
        hits += e.is_hit();
        const bool same_ids = e.instance_id == a.instance_id && e.prim_id == a.prim_id;
        // Ids may differ on a tie: both hit at the same t (a shared edge or coplanar
        // overlapping triangles).
        const bool same_hit =
            same_t(e.t, a.t, tolerance) && (same_ids || (e.is_hit() && a.is_hit()));
        const bool same_occlusion = expected.occluded[i] == actual.occluded[i];
        if (same_hit && same_occlusion) continue;
        if (grazes_edge(e, tolerance) || grazes_edge(a, tolerance)) {
            ++grazes;
            continue;
        }
        if (++mismatches <= 5)
            ADD_FAILURE() << "ray " << i << ": expected t=" << e.t << " inst=" << e.instance_id
                          << " prim=" << e.prim_id << " occluded=" << int(expected.occluded[i])
                          << ", got t=" << a.t << " inst=" << a.instance_id << " prim=" << a.prim_id
                          << " occluded=" << int(actual.occluded[i]);
    }
    EXPECT_EQ(mismatches, 0u);
    EXPECT_LE(double(grazes), tolerance.max_graze_fraction * double(expected.hits.size()))
        << grazes << " rays disagree at grazed edges";
    // A comparison on rays that all miss would prove nothing.
    EXPECT_GT(hits, expected.hits.size() / 50) << "too few rays hit the scene";
}

/// The .glb files in the shared scene folder (at least the nine of its MANIFEST).
inline std::vector<std::string> shared_scene_files() {
    std::vector<std::string> files;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(REBRAID_SHARED_SCENES, error))
        if (entry.path().extension() == ".glb") files.push_back(entry.path().filename().string());
    std::sort(files.begin(), files.end());
    return files;
}

/// A GoogleTest-safe name for a file name.
inline std::string test_name_of(const std::string& file) {
    std::string name = file.substr(0, file.find('.'));
    for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return name;
}

}  // namespace rebraid::test
