#include "embree_glue/dropin/embree_accel.h"

#include <tbb/parallel_for.h>

#if defined(__x86_64__) || defined(_M_X64) || defined(__i386__)
#include <immintrin.h>
#define REBRAID_GLUE_SSE 1
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "embree_glue/dropin/embree_interposer_registry.h"
#include "embree_glue/reference/embree_geometry.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"

namespace rebraid {
namespace {

/// The rounding allowed for in misses_bounds, relative to the size of the products it
/// subtracts: a few float epsilons, far below the box's padding.
constexpr float kLineTestTolerance = 8.0f * 1.1920929e-07f;

ObjectBvhBuilder make_object_builder(const EmbreeAccelSettings& settings) {
    if (settings.object_builder == EmbreeAccelObjectBuilder::embree)
        return glue::embree_object_bvh_builder(settings.embree_builder);
    return own_object_bvh_builder(settings.own_builder);
}

/// rtcGetDeviceProperty of the scene's device (0 without one).
ssize_t scene_device_property(RTCScene scene, RTCDeviceProperty property) {
    // rtcGetSceneDevice adds a reference to the device.
    const RTCDevice device = rtcGetSceneDevice(scene);
    if (device == nullptr) return 0;
    const ssize_t value = rtcGetDeviceProperty(device, property);
    rtcReleaseDevice(device);
    return value;
}

/// Same meshes (geometries, triangles, vertex counts) and same instances (geometries, ids,
/// meshes): only vertex positions and transforms may differ.
bool has_same_structure(const glue::ConvertedEmbreeScene& a, const glue::ConvertedEmbreeScene& b) {
    if (a.mesh_geometries != b.mesh_geometries || a.instance_ids != b.instance_ids ||
        a.instance_geometries != b.instance_geometries || a.triangle_scenes != b.triangle_scenes)
        return false;
    for (std::size_t m = 0; m < a.scene.meshes.size(); ++m) {
        const Mesh& mesh_a = a.scene.meshes[m];
        const Mesh& mesh_b = b.scene.meshes[m];
        if (mesh_a.positions.size() != mesh_b.positions.size() ||
            mesh_a.triangles != mesh_b.triangles)
            return false;
    }
    for (std::size_t i = 0; i < a.scene.instances.size(); ++i)
        if (a.scene.instances[i].mesh_id != b.scene.instances[i].mesh_id) return false;
    return true;
}

/// The re-braided top over `scene` with the given object BVHs, as build_rebraid_accel makes it.
std::unique_ptr<InstancedAccel> build_top(const Scene& scene, std::vector<ObjectBvh> object_bvhs,
                                          const RebraidSettings& settings,
                                          const BuildTimer& timer) {
    RebraidBuild build = build_rebraid(scene, object_bvhs, settings);
    AccelStats info;
    info.build_ms = timer.elapsed_ms();
    info.top_build_ms = build.top.build_ms;
    info.brefs = build.brefs;
    info.budget = build.budget;
    info.opened = build.opened;
    return std::make_unique<InstancedAccel>(scene, std::move(object_bvhs), std::move(build.top),
                                            info, settings.merge_settings());
}

/// The triangle test of Embree's mode for `converted`: watertight in robust mode.
TriangleTest triangle_test_for(const glue::ConvertedEmbreeScene& converted) {
    return converted.is_robust ? TriangleTest::watertight : TriangleTest::moller;
}

/// Whether `accel`'s closest-hit queries give Embree's own Möller terms in `arithmetic`
/// (EmbreeAccel::intersect_finishing_terms).
bool finishes_moller_terms(const InstancedAccel& accel, glue::EmbreeKernelArithmetic arithmetic) {
    return accel.simd_level() != SimdLevel::portable &&
           accel.triangle_test() == TriangleTest::moller &&
           arithmetic != glue::EmbreeKernelArithmetic::separate;
}

/// Embree's world-to-object map of each instance (index = InstanceId).
std::vector<AffineTransform> embree_world_to_object_maps(const Scene& scene) {
    std::vector<AffineTransform> maps;
    maps.reserve(scene.instances.size());
    for (const Instance& instance : scene.instances)
        maps.push_back(glue::embree_world_to_object(instance.object_to_world));
    return maps;
}

}  // namespace

void EmbreeAccelSettings::validate() const {
    if (object_builder != EmbreeAccelObjectBuilder::own &&
        object_builder != EmbreeAccelObjectBuilder::embree)
        throw Error("EmbreeAccelSettings: object_builder " + std::to_string(int(object_builder)) +
                    " is neither own nor embree");
    own_builder.validate();
    embree_builder.validate();
    rebraid.validate();
    if (rebraid.world_space_single_instances || rebraid.world_space_copy_budget != 0.0f)
        throw Error(
            "EmbreeAccelSettings: rebraid.world_space_single_instances and "
            "world_space_copy_budget are not supported: the drop-in traces each mesh in "
            "its object space, as Embree does");
    object_update.validate();
}

EmbreeAccel::EmbreeAccel(RTCScene scene, const EmbreeAccelSettings& settings)
    : scene_(scene), settings_(settings) {
    settings_.validate();
    if (scene_ == nullptr) throw Error("EmbreeAccel: the scene is null");
    is_ray_mask_supported_ =
        scene_device_property(scene_, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;
    ray_mask_unsupported_ = is_ray_mask_supported_ ? 0u : 1u;
    has_native_packets8_ =
        scene_device_property(scene_, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0;
    has_native_packets16_ =
        scene_device_property(scene_, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
    arithmetic_ = glue::detect_embree_kernel_arithmetic();
    converted_ = convert_now();
    embree_world_to_object_ = embree_world_to_object_maps(converted_.scene);
    object_builder_ = make_object_builder(settings_);
    accel_ = std::make_unique<InstancedAccel>(
        build_rebraid_accel(converted_.scene, object_builder_, settings_.rebraid));
    accel_->set_triangle_test(triangle_test_for(converted_));
    accel_->set_world_to_object(embree_world_to_object_);
    // Every query is screened first (turns_away): the root box's test would repeat it.
    accel_->set_culls_root_box(false);
    intersect1_ = intersect1_form();
    bounds_ = converted_.scene.bounds();
    pad_bounds();
    rtcRetainScene(scene_);  // last: a throwing constructor has nothing to release
}

EmbreeAccel::~EmbreeAccel() {
    rtcReleaseScene(scene_);
}

glue::ConvertedEmbreeScene EmbreeAccel::convert_now() const {
    if (glue::has_lost_records())
        throw Error(
            "EmbreeAccel: the drop-in's registry lost a record (out of memory while "
            "recording an Embree call); it cannot describe the scene");
    const std::optional<glue::RegisteredSceneSnapshot> snapshot =
        glue::snapshot_registered_scene(scene_);
    if (!snapshot) {
        if (!glue::is_interposer_active())
            throw Error(
                "EmbreeAccel: no Embree call of this program went through the drop-in's "
                "interposer: link rebraid::embree_dropin before libembree3");
        throw Error(
            "EmbreeAccel: the drop-in's registry does not know the scene (it was "
            "released, or created by code that calls Embree without the interposer)");
    }
    return glue::convert_embree_scene(*snapshot, is_ray_mask_supported_);
}

void EmbreeAccel::pad_bounds() {
    // The box of the top level's root: the traversal tests every ray against the boxes it
    // holds first, so a ray that misses it by more than rounding finds no hit. The margin is
    // far above the rounding of either test.
    const BBox3f& box = accel_->top_level().bounds;
    float half[3];
    for (int a = 0; a < 3; ++a) {
        const float pad = 1e-3f * (box.max[a] - box.min[a]) +
                          1e-4f * std::max(std::abs(box.min[a]), std::abs(box.max[a])) + 1e-6f;
        const float low = box.min[a] - pad, high = box.max[a] + pad;
        padded_centre_[a] = 0.5f * (low + high);
        // Rounded up, so that the box stays around [low, high] whatever the centre's rounding.
        half[a] = 0.5f * (high - low) * (1.0f + 1e-6f);
    }
    padded_centre_[3] = 0.0f;
    for (int a = 0; a < 3; ++a) {
        padded_half_yzx_[a] = half[(a + 1) % 3];
        padded_half_zxy_[a] = half[(a + 2) % 3];
    }
    padded_half_yzx_[3] = padded_half_zxy_[3] = 0.0f;
}

// Inline, and always: each intersect1 form compiles it for its own instruction set.
[[gnu::always_inline]] inline bool EmbreeAccel::misses_bounds(const RTCRay& ray) const noexcept {
    // The separating axes of a line and a box: the line misses the box exactly when, for
    // some axis i, |((centre - org) x dir)_i| > half_j |dir_k| + half_k |dir_j| ((i, j, k)
    // cyclic: the box seen down the line is a hexagon whose edge normals these are). No
    // division, and a dependency chain a third as long as the slab test's, which every ray
    // waits on here. The ray's interval is not looked at: a ray whose line crosses the box
    // goes on to the traversal. Each product's rounding is allowed for by a few epsilons of
    // the products' size; NaN or infinities in the ray compare false and go on as well.
#ifdef REBRAID_GLUE_SSE
    // RTCRay keeps (org, tnear) and (dir, time) in two groups of four floats: one load each
    // (lane 3 is left out of the answer). The box's half extents are kept in the two lane
    // orders the test multiplies them in.
    static_assert(offsetof(RTCRay, tnear) == 12 && offsetof(RTCRay, dir_x) == 16 &&
                  offsetof(RTCRay, time) == 28);
    const __m128 to_centre = _mm_sub_ps(_mm_load_ps(padded_centre_), _mm_loadu_ps(&ray.org_x));
    const __m128 dir = _mm_loadu_ps(&ray.dir_x);
    const auto yzx = [](__m128 v) { return _mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 0, 2, 1)); };
    const auto zxy = [](__m128 v) { return _mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 1, 0, 2)); };
    const __m128 sign = _mm_set1_ps(-0.0f);
    const __m128 dir_yzx = yzx(dir), dir_zxy = zxy(dir);
    const __m128 first = _mm_mul_ps(yzx(to_centre), dir_zxy);
    const __m128 second = _mm_mul_ps(zxy(to_centre), dir_yzx);
    const __m128 cross = _mm_andnot_ps(sign, _mm_sub_ps(first, second));
    const __m128 size = _mm_add_ps(_mm_andnot_ps(sign, first), _mm_andnot_ps(sign, second));
    const __m128 reach =
        _mm_add_ps(_mm_mul_ps(_mm_load_ps(padded_half_yzx_), _mm_andnot_ps(sign, dir_zxy)),
                   _mm_mul_ps(_mm_load_ps(padded_half_zxy_), _mm_andnot_ps(sign, dir_yzx)));
    const __m128 limit = _mm_add_ps(reach, _mm_mul_ps(size, _mm_set1_ps(kLineTestTolerance)));
    return (_mm_movemask_ps(_mm_cmpgt_ps(cross, limit)) & 7) != 0;
#else
    const float to_centre[3] = {padded_centre_[0] - ray.org_x, padded_centre_[1] - ray.org_y,
                                padded_centre_[2] - ray.org_z};
    const float dir[3] = {ray.dir_x, ray.dir_y, ray.dir_z};
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        const float first = to_centre[j] * dir[k], second = to_centre[k] * dir[j];
        const float reach =
            padded_half_yzx_[i] * std::abs(dir[k]) + padded_half_zxy_[i] * std::abs(dir[j]);
        const float limit = reach + (std::abs(first) + std::abs(second)) * kLineTestTolerance;
        if (std::abs(first - second) > limit) return true;
    }
    return false;
#endif
}

[[gnu::always_inline]] inline bool EmbreeAccel::turns_away(const RTCRay& ray) const noexcept {
    // Embree's inactive rays (tnear > tfar, or NaN bounds) and rays whose mask no geometry
    // shares are left untouched.
    return !(ray.tnear <= ray.tfar) || (ray.mask | ray_mask_unsupported_) == 0 ||
           misses_bounds(ray);
}

namespace {

/// True when a coordinate of `ray` is zero: mapping it through an identity transform, as
/// Embree does for an instance placed by the identity (which our traversal enters with the
/// world ray itself), may flip a zero's sign.
bool has_zero_coordinate(const Ray& ray) {
    return ray.org.x == 0.0f || ray.org.y == 0.0f || ray.org.z == 0.0f || ray.dir.x == 0.0f ||
           ray.dir.y == 0.0f || ray.dir.z == 0.0f;
}

/// The traversal's own t, u, v and the normal of the hit triangle: for a grazing hit Embree's
/// rounding calls parallel (which it would not report). Rare, so out of line.
[[gnu::noinline, gnu::cold]] void write_own_attributes(RTCRayHit& rayhit, const Hit& hit,
                                                       const HitTriangle& triangle) {
    const TriangleVerts corners = triangle.corners();
    const Vec3f normal = cross(corners.v2 - corners.v0, corners.v0 - corners.v1);
    rayhit.ray.tfar = hit.t;
    rayhit.hit.Ng_x = normal.x;
    rayhit.hit.Ng_y = normal.y;
    rayhit.hit.Ng_z = normal.z;
    rayhit.hit.u = hit.u;
    rayhit.hit.v = hit.v;
}

/// Writes a hit into `rayhit`: Embree's attributes where its arithmetic gave them, else
/// write_own_attributes.
inline void write_hit(RTCRayHit& rayhit, const Hit& hit, const glue::EmbreeHitIds& ids,
                      const std::optional<glue::EmbreeHitAttributes>& embree_hit,
                      const HitTriangle& triangle) {
    RTCRay& ray = rayhit.ray;
    if (embree_hit) {
        // Embree's t when it lies in the ray's interval (it does but for rounding at the
        // interval's ends), so that t, u and v describe the same point.
        const float t = embree_hit->t;
        ray.tfar = t >= ray.tnear && t <= ray.tfar ? t : hit.t;
        rayhit.hit.Ng_x = embree_hit->geometry_normal.x;
        rayhit.hit.Ng_y = embree_hit->geometry_normal.y;
        rayhit.hit.Ng_z = embree_hit->geometry_normal.z;
        rayhit.hit.u = embree_hit->u;
        rayhit.hit.v = embree_hit->v;
    } else {
        write_own_attributes(rayhit, hit, triangle);
    }
    rayhit.hit.primID = hit.prim_id;
    rayhit.hit.geomID = ids.geom_id;
    rayhit.hit.instID[0] = ids.inst_id;
}

}  // namespace

/// Embree's attributes of each closer hit as the query finds it (the last one computed is the
/// closest hit's), so that their recomputation overlaps the rest of the traversal instead of
/// following it: where the query does not give Embree's own terms.
struct EmbreeAccel::PendingAttributes {
    const EmbreeAccel& accel;
    const Ray& ray;
    std::optional<glue::EmbreeHitAttributes> attributes;

    static void on_closer_hit(void* context, InstanceId instance, const HitTriangle& triangle) {
        auto& pending = *static_cast<PendingAttributes*>(context);
        pending.attributes = pending.accel.recomputed_attributes(pending.ray, instance, triangle);
    }
};

std::optional<glue::EmbreeHitAttributes> EmbreeAccel::recomputed_attributes(
    const Ray& ray, InstanceId instance, const HitTriangle& triangle) const noexcept {
    const bool is_instanced = converted_.instance_ids[instance].inst_id != RTC_INVALID_GEOMETRY_ID;
    const TriangleVerts corners = triangle.corners();
    return glue::embree_hit_attributes(ray,
                                       is_instanced ? &embree_world_to_object_[instance] : nullptr,
                                       {corners.v0, corners.v1, corners.v2}, arithmetic_);
}

void EmbreeAccel::intersect_observing(RTCRayHit& rayhit) const noexcept {
    const Ray ray = glue::from_embree_ray(rayhit.ray);
    PendingAttributes pending{*this, ray, std::nullopt};
    const CloserHitObserver observer{&PendingAttributes::on_closer_hit, &pending};
    const LocatedHit located = accel_->intersect_located(ray, &observer);
    if (!located.hit.is_hit()) return;
    write_hit(rayhit, located.hit, converted_.instance_ids[located.hit.instance_id],
              pending.attributes, located.triangle);
}

template <float (*kEstimate)(float)>
void EmbreeAccel::intersect_finishing_terms(RTCRayHit& rayhit) const noexcept {
    // Our traversal finds the triangle and t; the reported attributes must be Embree's to the
    // last bit. The SIMD kernels' Möller test computed Embree's own terms (the ray in Embree's
    // object space: set_world_to_object), so Embree's reciprocal finishes them; they are
    // computed again the way Embree computes them (its world-to-object map, its kernel's
    // rounding) only where the query ran another test, or entered an instance placed by the
    // identity with the world ray while a zero coordinate may differ in sign from Embree's.
    const Ray ray = glue::from_embree_ray(rayhit.ray);
    const LocatedHit located = accel_->intersect_located(ray, nullptr);
    const Hit& hit = located.hit;
    if (!hit.is_hit()) return;
    const glue::EmbreeHitIds& ids = converted_.instance_ids[hit.instance_id];
    const HitTriangle& triangle = located.triangle;
    const bool keeps_terms =
        triangle.has_moller_terms &&
        !(ids.inst_id != RTC_INVALID_GEOMETRY_ID &&
          accel_->instance_targets()[hit.instance_id].space == InstanceTarget::kWorldSpace &&
          has_zero_coordinate(ray));
    const MollerTerms& terms = triangle.moller_terms;
    write_hit(rayhit, hit, ids,
              keeps_terms
                  ? glue::embree_fused_attributes_from_terms(terms, kEstimate(terms.abs_den))
                  : recomputed_attributes(ray, hit.instance_id, triangle),
              triangle);
}

// Each form is compiled for the instruction set of the Embree kernels it stands for (chosen
// only where Embree runs them): the fused multiply-adds and the estimate inline with the rest.
// Out of line (noinline): the forms of intersect1 call them past the screen.
#if defined(REBRAID_GLUE_HAS_RCP_ESTIMATES) && (defined(__GNUC__) || defined(__clang__))
#define REBRAID_GLUE_TARGET(isa) __attribute__((target(isa)))
#else
#define REBRAID_GLUE_TARGET(isa)
#endif

REBRAID_GLUE_TARGET("avx2,fma")
__attribute__((noinline, flatten)) void EmbreeAccel::intersect_finishing_terms_12(
    RTCRayHit& rayhit) const noexcept {
    intersect_finishing_terms<&glue::embree_reciprocal_estimate_12>(rayhit);
}

REBRAID_GLUE_TARGET("avx512f")
__attribute__((noinline, flatten)) void EmbreeAccel::intersect_finishing_terms_14(
    RTCRayHit& rayhit) const noexcept {
    intersect_finishing_terms<&glue::embree_reciprocal_estimate_14>(rayhit);
}

void EmbreeAccel::intersect1_observing(const EmbreeAccel& accel, RTCRayHit& rayhit) noexcept {
    if (!accel.turns_away(rayhit.ray)) accel.intersect_observing(rayhit);
}

REBRAID_GLUE_TARGET("avx2,fma")
void EmbreeAccel::intersect1_finishing_12(const EmbreeAccel& accel, RTCRayHit& rayhit) noexcept {
    if (!accel.turns_away(rayhit.ray)) accel.intersect_finishing_terms_12(rayhit);
}

REBRAID_GLUE_TARGET("avx512f")
void EmbreeAccel::intersect1_finishing_14(const EmbreeAccel& accel, RTCRayHit& rayhit) noexcept {
    if (!accel.turns_away(rayhit.ray)) accel.intersect_finishing_terms_14(rayhit);
}

#undef REBRAID_GLUE_TARGET

EmbreeAccel::Intersect1 EmbreeAccel::intersect1_form() const {
    if (!finishes_moller_terms(*accel_, arithmetic_)) return &EmbreeAccel::intersect1_observing;
    return arithmetic_ == glue::EmbreeKernelArithmetic::fused_rcp14
               ? &EmbreeAccel::intersect1_finishing_14
               : &EmbreeAccel::intersect1_finishing_12;
}

void EmbreeAccel::occluded1(RTCRay& in) const noexcept {
    if (turns_away(in)) return;
    const Ray ray = glue::from_embree_ray(in);
    if (accel_->occluded(ray)) in.tfar = -std::numeric_limits<float>::infinity();
}

EmbreeUpdateReport EmbreeAccel::update() {
    const BuildTimer timer;
    EmbreeUpdateReport report;
    glue::ConvertedEmbreeScene next = convert_now();
    std::unique_ptr<InstancedAccel> next_accel;
    if (!has_same_structure(converted_, next)) {
        report.is_full_rebuild = true;
        report.meshes_rebuilt = std::uint32_t(next.scene.meshes.size());
        next_accel = std::make_unique<InstancedAccel>(
            build_rebraid_accel(next.scene, object_builder_, settings_.rebraid));
        updaters_.clear();
    } else {
        next.scene.validate();
        std::vector<MeshId> changed;
        for (std::size_t m = 0; m < next.scene.meshes.size(); ++m)
            if (next.scene.meshes[m].positions != converted_.scene.meshes[m].positions)
                changed.push_back(MeshId(m));
        bool is_moved = false;
        for (std::size_t i = 0; i < next.scene.instances.size(); ++i)
            is_moved = is_moved || next.scene.instances[i].object_to_world !=
                                       converted_.scene.instances[i].object_to_world;
        if (changed.empty() && !is_moved) {
            // A commit that changed nothing the structure depends on: it stays as it is.
            report.meshes_unchanged = std::uint32_t(next.scene.meshes.size());
            accel_->set_triangle_test(triangle_test_for(next));
            converted_ = std::move(next);
            intersect1_ = intersect1_form();
            report.update_ms = timer.elapsed_ms();
            return report;
        }
        // Unchanged object BVHs are copied: InstancedAccel owns its BVHs, and the current
        // structure must stay intact until the new one is complete.
        std::vector<ObjectBvh> object_bvhs = accel_->object_bvhs();
        updaters_.resize(next.scene.meshes.size());
        for (MeshId m : changed)
            if (!updaters_[m])
                updaters_[m] = std::make_unique<ObjectBvhUpdater>(settings_.object_update);
        std::vector<UpdateStrategy> applied(changed.size());
        tbb::parallel_for(std::size_t(0), changed.size(), [&](std::size_t i) {
            const MeshId m = changed[i];
            applied[i] = updaters_[m]->update(next.scene.meshes[m], object_bvhs[m]).applied;
        });
        for (UpdateStrategy strategy : applied)
            ++(strategy == UpdateStrategy::rebuild ? report.meshes_rebuilt : report.meshes_refit);
        report.meshes_unchanged = std::uint32_t(next.scene.meshes.size() - changed.size());
        // Moving instances and deforming meshes update the merged top level, which rebuilds
        // in milliseconds; the world tree, a build over every instanced triangle, is made
        // with full builds only.
        RebraidSettings top_settings = settings_.rebraid;
        top_settings.world_tree = false;
        next_accel = build_top(next.scene, std::move(object_bvhs), top_settings, timer);
    }
    next_accel->set_triangle_test(triangle_test_for(next));
    std::vector<AffineTransform> world_to_object = embree_world_to_object_maps(next.scene);
    next_accel->set_world_to_object(world_to_object);
    next_accel->set_culls_root_box(false);
    bounds_ = next.scene.bounds();
    converted_ = std::move(next);
    accel_ = std::move(next_accel);
    pad_bounds();  // of the new top level
    embree_world_to_object_ = std::move(world_to_object);
    intersect1_ = intersect1_form();
    report.update_ms = timer.elapsed_ms();
    return report;
}

}  // namespace rebraid
