#pragma once

// Comparing the answers of two structures on the same rays, with the tolerance the project
// promises: same closest-hit t within 1e-4 relative, same instance and primitive ids and
// barycentrics (within 1e-3, or what rounding the hit point allows on a small triangle;
// unless two triangles are hit at the same t: a tie either may win, checked to be a real one
// and capped), same occlusion.

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "rebraid/core/accel.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/scene.h"
#include "support/hit_point.h"

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
    /// Largest fraction of rays allowed to differ where the answer is fragile: at a grazed
    /// edge, or in the barycentrics of a sliver triangle.
    double max_fragile_fraction = 1e-3;
    /// A triangle is a sliver when its area is below this fraction of its longest edge
    /// squared: its barycentrics are ill-conditioned, so two correct kernels differ in them.
    float sliver_quality = 1e-2f;
    /// Largest fraction of rays whose closest hit may name another triangle hit at the same
    /// t (an edge shared by two triangles, coplanar overlapping triangles): a tie either
    /// structure may win. Buildings (city, fzk_haus) share edges and faces: up to 0.6 %.
    double max_tie_fraction = 1e-2;
    /// Smallest fraction of rays that must hit: a comparison of misses proves nothing.
    double min_hit_fraction = 1e-2;
    /// Largest difference of u or v between two hits on the same triangle.
    float barycentric = 1e-3f;
};

inline Tolerance tolerance_for(const BBox3f& bounds) {
    const Vec3f m = max(max(bounds.min, -bounds.min), max(bounds.max, -bounds.max));
    return {std::max({m.x, m.y, m.z, 1e-30f})};
}

/// Same t: within 1e-4 relative, or within 64 ulps of the scene's magnitude measured along
/// the ray (t is in units of the direction, which need not be normalised).
inline bool same_t(float a, float b, const Tolerance& tolerance, float direction_length = 1.0f) {
    if (std::isinf(a) || std::isinf(b)) return a == b;
    const float absolute = tolerance.scene_magnitude * 0x1.0p-18f / direction_length;
    return std::fabs(a - b) <= 1e-4f * std::max(std::fabs(a), std::fabs(b)) + absolute;
}

inline bool grazes_edge(const Hit& hit, const Tolerance& tolerance) {
    return hit.is_hit() && std::min({hit.u, hit.v, 1.0f - hit.u - hit.v}) < tolerance.edge_graze;
}

/// The corners of a hit's triangle in world space.
struct WorldTriangle {
    Vec3f a, b, c;
    float twice_area() const { return length(cross(b - a, c - a)); }
    float longest_edge_squared() const {
        return std::max({dot(b - a, b - a), dot(c - b, c - b), dot(a - c, a - c)});
    }
};

/// The world-space corners of the triangle `hit` names.
inline WorldTriangle world_triangle(const Scene& scene, const Hit& hit) {
    const Instance& instance = scene.instances[hit.instance_id];
    const auto corners = scene.meshes[instance.mesh_id].corners(hit.prim_id);
    return {instance.object_to_world.transform_point(corners[0]),
            instance.object_to_world.transform_point(corners[1]),
            instance.object_to_world.transform_point(corners[2])};
}

/// How far the barycentrics of a hit on `hit`'s triangle may move when the hit point moves by
/// 64 ulps of the scene's magnitude within the triangle's plane: that distance over the
/// triangle's smallest height (world space). Rays entering an instance are mapped into its
/// space, and a small triangle far from the origin turns that mapping's rounding into
/// barycentric differences well above Tolerance::barycentric; two correct structures that map
/// differently (or not at all, as a flat one) then differ by up to this much.
inline float barycentric_rounding(const Scene& scene, const Hit& hit, const Tolerance& tolerance) {
    const WorldTriangle triangle = world_triangle(scene, hit);
    const float smallest_height =
        triangle.twice_area() / std::sqrt(triangle.longest_edge_squared());
    return tolerance.scene_magnitude * 0x1.0p-18f / smallest_height;
}

/// True when `hit` names a sliver triangle (see Tolerance::sliver_quality), in world space.
inline bool hits_sliver(const Scene& scene, const Hit& hit, const Tolerance& tolerance) {
    const WorldTriangle triangle = world_triangle(scene, hit);
    return !(triangle.twice_area() >= tolerance.sliver_quality * triangle.longest_edge_squared());
}

/// True when `hit`'s instance, primitive and barycentrics name the world-space point the
/// ray reaches at hit.t (within 1e-5 of the scene's magnitude, plus 1e-5 of the distance
/// travelled): the triangle a hit names is really hit there.
inline bool hit_names_its_point(const Scene& scene, const Ray& ray, const Hit& hit,
                                const Tolerance& tolerance) {
    if (!(hit.u >= -tolerance.edge_graze && hit.v >= -tolerance.edge_graze &&
          hit.u + hit.v <= 1.0f + tolerance.edge_graze))
        return false;
    return hit_point_error(scene, ray, hit) <=
           1e-5f * (tolerance.scene_magnitude + length(ray.dir * hit.t));
}

/// What a comparison of two structures' answers found.
struct ComparisonCounts {
    std::size_t rays = 0;
    std::size_t hits = 0;        ///< rays the expected structure hits
    std::size_t ties = 0;        ///< same t, another triangle that is really hit there
    std::size_t fragile = 0;     ///< differences excused at a grazed edge or on a sliver
    std::size_t mismatches = 0;  ///< everything else that differs
};

/// Compares `actual` with `expected` (answers to `rays` over `scene`) ray by ray: the same
/// miss or hit, the same t, the same instance and primitive ids and (on the same triangle)
/// the same u and v, the same occlusion. Ids
/// may differ only on a tie: both hits at the same t, each naming a triangle that really holds the
/// point there; ties are counted and capped. A difference where either hit grazes an edge is
/// counted and capped too, as are different barycentrics on a sliver triangle. Asserts no
/// mismatches, the caps, and a minimum share of hits; reports the first few mismatches with their
/// rays. Returns the counts.
inline ComparisonCounts expect_same_answers(const Scene& scene, const std::vector<Ray>& rays,
                                            const AccelAnswers& expected,
                                            const AccelAnswers& actual,
                                            const Tolerance& tolerance) {
    ComparisonCounts counts;
    EXPECT_EQ(expected.hits.size(), rays.size());
    EXPECT_EQ(actual.hits.size(), rays.size());
    if (expected.hits.size() != rays.size() || actual.hits.size() != rays.size()) return counts;
    counts.rays = rays.size();
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const Ray& ray = rays[i];
        const Hit& e = expected.hits[i];
        const Hit& a = actual.hits[i];
        counts.hits += e.is_hit();
        bool is_tie = false, is_sliver_difference = false;
        bool agrees = e.is_hit() == a.is_hit();
        if (agrees && e.is_hit()) {
            agrees = same_t(e.t, a.t, tolerance, length(ray.dir));
            if (agrees && (e.instance_id != a.instance_id || e.prim_id != a.prim_id)) {
                is_tie = true;
                agrees = hit_names_its_point(scene, ray, a, tolerance) &&
                         hit_names_its_point(scene, ray, e, tolerance);
            } else if (agrees) {
                const float allowed =
                    std::max(tolerance.barycentric, barycentric_rounding(scene, a, tolerance));
                agrees = std::fabs(e.u - a.u) <= allowed && std::fabs(e.v - a.v) <= allowed;
                is_sliver_difference = !agrees && hits_sliver(scene, a, tolerance);
            }
        }
        agrees = agrees && expected.occluded[i] == actual.occluded[i];
        if (agrees) {
            counts.ties += is_tie;
            continue;
        }
        if (is_sliver_difference || grazes_edge(e, tolerance) || grazes_edge(a, tolerance)) {
            ++counts.fragile;
            continue;
        }
        if (++counts.mismatches <= 5)
            ADD_FAILURE() << "ray " << i << " (org " << ray.org.x << " " << ray.org.y << " "
                          << ray.org.z << ", dir " << ray.dir.x << " " << ray.dir.y << " "
                          << ray.dir.z << ", t [" << ray.tnear << ", " << ray.tfar
                          << "]): expected t=" << e.t << " inst=" << e.instance_id
                          << " prim=" << e.prim_id << " u=" << e.u << " v=" << e.v
                          << " occluded=" << int(expected.occluded[i]) << ", got t=" << a.t
                          << " inst=" << a.instance_id << " prim=" << a.prim_id << " u=" << a.u
                          << " v=" << a.v << " occluded=" << int(actual.occluded[i]);
    }
    const double ray_count = double(rays.size());
    EXPECT_EQ(counts.mismatches, 0u);
    EXPECT_LE(double(counts.fragile), tolerance.max_fragile_fraction * ray_count)
        << counts.fragile << " rays disagree at grazed edges or on slivers";
    EXPECT_LE(double(counts.ties), tolerance.max_tie_fraction * ray_count)
        << counts.ties << " rays hit another triangle at the same t";
    EXPECT_GE(double(counts.hits), tolerance.min_hit_fraction * ray_count)
        << "too few rays hit the scene";
    return counts;
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
