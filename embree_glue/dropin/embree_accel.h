#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "embree_glue/dropin/embree_accel_scene.h"
#include "embree_glue/reference/embree_bvh_builder.h"
#include "embree_glue/reference/embree_hit_attributes.h"
#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/accel.h"
#include "rebraid/dynamic/object_bvh_update.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/instanced_accel.h"

namespace rebraid {

/// Who builds an EmbreeAccel's object BVHs.
enum class EmbreeAccelObjectBuilder {
    own,     ///< the project's parallel binned-SAH builder
    embree,  ///< Embree's rtcBuildBVH (rebraid::glue::build_object_bvh_embree)
};

/// Parameters of an EmbreeAccel. Defaults are the project's defaults (bench/RESULTS.md).
struct EmbreeAccelSettings {
    /// Which builder makes the object BVHs.
    EmbreeAccelObjectBuilder object_builder = EmbreeAccelObjectBuilder::own;
    /// The project's builder, when `object_builder` is own (with spatial splits; update()
    /// refits, rotates and rebuilds as object_update says).
    BuildSettings own_builder = static_object_build_settings();
    /// rtcBuildBVH, when `object_builder` is embree.
    glue::EmbreeBvhBuilderSettings embree_builder{};
    /// The re-braided top level. Every mesh keeps its object space
    /// (world_space_single_instances off, world_space_copy_budget 0; validate() rejects
    /// others): Embree computes an instance's hits there, which the drop-in reproduces bit for
    /// bit, and update() keeps object BVHs while instances move. The object subtrees of
    /// placed instances are merged into the traced tree (merge_placed_instances: world-space
    /// boxes, object-space triangles, the same bits) while their copies hold at most 4 times
    /// the object BVHs' nodes: Embree's viewer under the preload traced brainstem, fzk_haus
    /// and two_cylinder_engine 2-5 % faster, at 0.4-1.1 MB more (docs/design.md). For 2 to
    /// 100 instances and at most a million instanced triangles, at most twice the meshes', a
    /// full build traces a world tree instead (world_tree: rebraid/top_level/world_tree.h;
    /// docs/design.md, "World trees"), and update() after instances or vertices moved the
    /// merged top level.
    RebraidSettings rebraid = [] {
        RebraidSettings settings;
        settings.world_space_single_instances = false;
        settings.world_space_copy_budget = 0.0f;
        settings.merge_placed_instances = true;
        settings.merge_placed_node_budget = 4.0f;
        settings.world_tree = true;
        return settings;
    }();
    /// How update() brings the object BVHs of deformed meshes up to date (refit, rotations,
    /// restructuring, rebuild, or automatic: refit until the SAH degrades, then rebuild).
    ObjectBvhUpdateSettings object_update{};

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;
};

/// What EmbreeAccel::update() did.
struct EmbreeUpdateReport {
    /// The scene's structure changed (geometries attached, detached, enabled, disabled,
    /// triangle counts or indices...), so everything was converted and built again.
    bool is_full_rebuild = false;
    /// Object BVHs built again: every one after a structural change, else those of deformed
    /// meshes whose update strategy chose a rebuild.
    std::uint32_t meshes_rebuilt = 0;
    /// Object BVHs of deformed meshes updated in place (refit, rotations or restructuring).
    std::uint32_t meshes_refit = 0;
    /// Object BVHs kept as they were.
    std::uint32_t meshes_unchanged = 0;
    /// Wall-clock time of the update, conversion included.
    double update_ms = 0.0;
};

/// Re-braiding for an application that already builds Embree scenes: built from a committed
/// RTCScene whose geometries are triangle meshes and instances of scenes of triangle meshes,
/// it answers rays with the same ids, barycentrics and normals rtcIntersect1 and rtcOccluded1
/// give on that scene.
///
/// Embree's API cannot list a scene's contents, so the application must be linked against
/// rebraid::embree_dropin, whose interposer records its Embree calls (docs/embree.md,
/// "Why an interposer"). The scene is converted once (vertices and indices copied out
/// of the application's buffers; see convert_embree_scene for what is supported and what throws),
/// then object BVHs are built for each distinct triangle geometry and a re-braided top level
/// over all instances. The scene is retained until destruction.
///
/// Queries are const and safe from many threads at once; update() is not (no query may run
/// during it).
class EmbreeAccel {
public:
    /// Throws rebraid::Error when the registry does not know `scene`, for anything the
    /// conversion rejects (naming the scene and geometry) and for invalid settings.
    explicit EmbreeAccel(RTCScene scene, const EmbreeAccelSettings& settings = {});
    ~EmbreeAccel();

    EmbreeAccel(const EmbreeAccel&) = delete;
    EmbreeAccel& operator=(const EmbreeAccel&) = delete;

    /// rtcIntersect1 with Embree's conventions: a ray with tnear > tfar (or NaN bounds) is
    /// inactive and, like a miss, leaves `rayhit` untouched (initialise hit.geomID to
    /// RTC_INVALID_GEOMETRY_ID, as Embree requires). A hit sets ray.tfar, hit.u, hit.v, hit.Ng
    /// (unnormalised, in the object space of the instance for instanced geometry: what Embree
    /// gives), hit.geomID, hit.primID and hit.instID[0] (RTC_INVALID_GEOMETRY_ID for a
    /// triangle geometry of the scene itself). ray.mask: when Embree was built with ray masks
    /// (rtcGetDeviceProperty RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) a ray with mask 0 sees
    /// nothing, any other mask sees everything (every geometry has the default mask, or
    /// construction threw). ray.time, ray.flags and ray.id are ignored (no motion blur).
    /// Once the project's traversal has found the hit, tfar, u, v and Ng are computed again as
    /// Embree computes them (glue::embree_hit_attributes: its world-to-object map and the
    /// rounding of the kernels it runs on this CPU), so where both find the same triangle they
    /// equal rtcIntersect1's to the last bit (measured: Embree's AVX2 kernels on every shared
    /// scene, its AVX and SSE4.2 kernels on random instanced triangles; its AVX-512 kernels
    /// may differ in the last bit).
    void intersect1(RTCRayHit& rayhit) const noexcept { intersect1_(*this, rayhit); }
    /// rtcOccluded1: sets ray.tfar to -inf when any hit exists in [tnear, tfar], else leaves
    /// the ray untouched. Same ray conventions as intersect1.
    void occluded1(RTCRay& ray) const noexcept;
    /// Whether Embree traces packets of `width` rays (4, 8 or 16) with packet kernels of its
    /// own on the scene's device (rtcGetDeviceProperty RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED
    /// and RAY16; packets of 4 always). Where not, Embree 3 traces an 8- or 16-ray packet as a
    /// stream, whose lanes are active when tnear <= tfar whatever the valid mask says (a CPU
    /// without AVX-512 has no 16-wide kernels): the preload answers such packets that way too.
    bool has_native_packets(unsigned int width) const noexcept {
        return width == 4 || (width == 8 && has_native_packets8_) ||
               (width == 16 && has_native_packets16_);
    }

    /// After the application changed vertex buffers or instance transforms (or anything else)
    /// and committed: converts the scene again, updates the object BVHs of meshes whose
    /// vertices changed with settings.object_update (one ObjectBvhUpdater per mesh), keeps the
    /// others, and builds the top level again. When the scene's structure changed, builds
    /// everything again. Throws as the constructor does; the structure is then left as it was
    /// before the call.
    EmbreeUpdateReport update();

    /// The scene this was built from.
    RTCScene rtc_scene() const { return scene_; }
    /// The structure in the project's terms (instance ids of converted_scene()).
    const InstancedAccel& accel() const { return *accel_; }
    /// The scene as converted, with the ids back to Embree.
    const glue::ConvertedEmbreeScene& converted_scene() const { return converted_; }
    /// World-space bounds of everything the structure can hit.
    const BBox3f& bounds() const { return bounds_; }
    /// Statistics of the structure (as `rebraid stats` reports them).
    AccelStats stats() const { return accel_->stats(); }

private:
    /// Conversion of the scene as the registry sees it now.
    glue::ConvertedEmbreeScene convert_now() const;
    void pad_bounds();
    /// True when `ray` certainly misses every triangle: its line misses the padded scene
    /// bounds.
    bool misses_bounds(const RTCRay& ray) const noexcept;
    /// True when intersect1 leaves `ray` untouched without a traversal: inactive, masked off
    /// or missing the padded bounds.
    bool turns_away(const RTCRay& ray) const noexcept;
    /// intersect1 in one of the forms below, chosen with the structure (intersect1_form):
    /// each screens the ray (turns_away) compiled for the instruction set of the query it
    /// then calls, so that the screen, which every ray pays and most rays of a frame that
    /// frames a whole scene end at, takes the shorter encodings where the CPU has them. The
    /// query past the screen is out of line: the rays turned away return without paying for
    /// the traversal's registers and stack.
    using Intersect1 = void (*)(const EmbreeAccel& accel, RTCRayHit& rayhit) noexcept;
    Intersect1 intersect1_form() const;
    static void intersect1_observing(const EmbreeAccel& accel, RTCRayHit& rayhit) noexcept;
    static void intersect1_finishing_12(const EmbreeAccel& accel, RTCRayHit& rayhit) noexcept;
    static void intersect1_finishing_14(const EmbreeAccel& accel, RTCRayHit& rayhit) noexcept;
    /// Where the query does not give Embree's own Möller terms: Embree's attributes computed
    /// again for each closer hit as it is found.
    void intersect_observing(RTCRayHit& rayhit) const noexcept;
    /// Where it does: the closest hit's terms finished with Embree's reciprocal, which starts
    /// from the estimate `kEstimate` gives.
    template <float (*kEstimate)(float)>
    void intersect_finishing_terms(RTCRayHit& rayhit) const noexcept;
    /// For Embree's AVX2 kernels (the 12-bit estimate): compiled for AVX2 and FMA.
    void intersect_finishing_terms_12(RTCRayHit& rayhit) const noexcept;
    /// For its AVX-512 kernels (the 14-bit estimate): compiled for AVX-512.
    void intersect_finishing_terms_14(RTCRayHit& rayhit) const noexcept;
    /// Embree's attributes of each closer hit as the traversal finds it (embree_accel.cpp).
    struct PendingAttributes;
    /// Embree's attributes of the hit of `ray` on `triangle` of `instance`, computed again
    /// from the triangle's corners as Embree computes them.
    std::optional<glue::EmbreeHitAttributes> recomputed_attributes(
        const Ray& ray, InstanceId instance, const HitTriangle& triangle) const noexcept;

    RTCScene scene_ = nullptr;
    EmbreeAccelSettings settings_;
    ObjectBvhBuilder object_builder_;
    bool is_ray_mask_supported_ = false;
    /// 1 where Embree ignores ray masks, else 0: a ray is masked off when its mask or'd with
    /// this is 0 (one test where two branches were).
    std::uint32_t ray_mask_unsupported_ = 1;
    bool has_native_packets8_ = false;
    bool has_native_packets16_ = false;
    /// How Embree rounds on this machine: the hit attributes are computed the same way.
    glue::EmbreeKernelArithmetic arithmetic_ = glue::EmbreeKernelArithmetic::separate;
    /// intersect1's form (intersect1_form): where the structure's queries give Embree's own
    /// Möller terms (a SIMD kernel, the Möller test, fused arithmetic), the closest hit's
    /// attributes are finished from them once, after the traversal, rather than computed for
    /// every closer hit as it is found.
    Intersect1 intersect1_ = nullptr;
    glue::ConvertedEmbreeScene converted_;
    std::unique_ptr<InstancedAccel> accel_;
    BBox3f bounds_;
    /// The top level's box with a margin, as its centre (x, y, z, then 0) and its half
    /// extents in the two orders misses_bounds multiplies them in ((y, z, x, 0) and
    /// (z, x, y, 0)): rays whose line misses it return before the traversal (most rays of a
    /// frame framing a whole scene miss every object).
    alignas(16) float padded_centre_[4] = {};
    alignas(16) float padded_half_yzx_[4] = {};
    alignas(16) float padded_half_zxy_[4] = {};
    /// index = InstanceId: Embree's world-to-object map of the instance (its float inverse of
    /// the registered transform, rounded as Embree rounds it); unused for root-scene meshes.
    std::vector<AffineTransform> embree_world_to_object_;
    /// index = MeshId: the state of each mesh's updates (reset by a full rebuild).
    std::vector<std::unique_ptr<ObjectBvhUpdater>> updaters_;
};

}  // namespace rebraid
