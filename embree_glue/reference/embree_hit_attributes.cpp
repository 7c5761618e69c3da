#include "embree_glue/reference/embree_hit_attributes.h"

#include <cmath>

namespace rebraid::glue {
namespace {

/// `x`, hidden from the optimiser: every product and sum here must round exactly as Embree's
/// code rounds it, and the compiler may not fuse a product that feeds a sum into one
/// multiply-add on its own (this file is built with -mfma, and GCC contracts by default).
/// Cheaper than turning contraction off for the file, which also kept the helpers below from
/// being inlined into the per-hit code.
inline float rounded(float x) {
#if defined(__x86_64__) || defined(__i386__)
    asm("" : "+x"(x));
#else
    asm("" : "+g"(x));
#endif
    return x;
}

/// Embree's multiply-adds in the AVX2 kernels: one rounding each.
struct FusedOps {
    static float madd(float a, float b, float c) { return std::fma(a, b, c); }    // a * b + c
    static float msub(float a, float b, float c) { return std::fma(a, b, -c); }   // a * b - c
    static float nmadd(float a, float b, float c) { return std::fma(-a, b, c); }  // c - a * b
    static float estimate(float x) { return embree_reciprocal_estimate_12(x); }
};

/// Embree's AVX-512 kernels: fused as AVX2's, with the 14-bit reciprocal estimate.
struct FusedRcp14Ops : FusedOps {
    static float estimate(float x) { return embree_reciprocal_estimate_14(x); }
};

/// Embree's multiply-adds in the SSE and AVX kernels: the product rounds, then the sum.
struct SeparateOps {
    static float madd(float a, float b, float c) { return rounded(a * b) + c; }
    static float msub(float a, float b, float c) { return rounded(a * b) - c; }
    static float nmadd(float a, float b, float c) { return c - rounded(a * b); }
    static float estimate(float x) { return embree_reciprocal_estimate_12(x); }
};

template <typename Ops>
Vec3f kernel_cross(Vec3f a, Vec3f b) {
    return {Ops::msub(a.y, b.z, rounded(a.z * b.y)), Ops::msub(a.z, b.x, rounded(a.x * b.z)),
            Ops::msub(a.x, b.y, rounded(a.y * b.x))};
}

template <typename Ops>
float kernel_dot(Vec3f a, Vec3f b) {
    return Ops::madd(a.x, b.x, Ops::madd(a.y, b.y, rounded(a.z * b.z)));
}

/// 1 / x as Embree's kernels compute it: the hardware estimate refined by one Newton step,
/// r + r * (1 - x * r). The estimate's table is the CPU's own, so on the same machine the
/// result is bit for bit Embree's.
template <typename Ops>
float kernel_reciprocal(float x) {
    const float estimate = Ops::estimate(x);
    return Ops::madd(estimate, Ops::nmadd(x, estimate, 1.0f), estimate);
}

template <typename Ops>
Vec3f kernel_transform_point(const AffineTransform& m, Vec3f p) {
    Vec3f out;
    for (int axis = 0; axis < 3; ++axis)
        out[axis] = Ops::madd(
            p.x, m.col_x[axis],
            Ops::madd(p.y, m.col_y[axis], Ops::madd(p.z, m.col_z[axis], m.translation[axis])));
    return out;
}

template <typename Ops>
Vec3f kernel_transform_vector(const AffineTransform& m, Vec3f d) {
    Vec3f out;
    for (int axis = 0; axis < 3; ++axis)
        out[axis] = Ops::madd(d.x, m.col_x[axis],
                              Ops::madd(d.y, m.col_y[axis], rounded(d.z * m.col_z[axis])));
    return out;
}

/// Embree's attributes from the test's terms: its reciprocal of |den| times each.
template <typename Ops>
std::optional<EmbreeHitAttributes> attributes_from_terms(const MollerTerms& terms) {
    return embree_attributes_from_reciprocal(terms, kernel_reciprocal<Ops>(terms.abs_den));
}

template <typename Ops>
std::optional<EmbreeHitAttributes> hit_attributes(const Ray& world_ray,
                                                  const AffineTransform* world_to_object,
                                                  const std::array<Vec3f, 3>& corners) {
    Vec3f org = world_ray.org, dir = world_ray.dir;
    if (world_to_object != nullptr) {
        org = kernel_transform_point<Ops>(*world_to_object, org);
        dir = kernel_transform_vector<Ops>(*world_to_object, dir);
    }
    const Vec3f& v0 = corners[0];
    const Vec3f edge1 = v0 - corners[1];
    const Vec3f edge2 = corners[2] - v0;
    MollerTerms terms;
    terms.normal = kernel_cross<Ops>(edge2, edge1);
    const Vec3f to_v0 = v0 - org;
    const Vec3f r = kernel_cross<Ops>(to_v0, dir);
    const float den = kernel_dot<Ops>(terms.normal, dir);
    if (!(den != 0.0f)) return std::nullopt;
    // Embree flips the sign bits of U, V and T when den is negative.
    const bool is_negative = std::signbit(den);
    auto with_den_sign = [is_negative](float x) { return is_negative ? -x : x; };
    terms.scaled_u = with_den_sign(kernel_dot<Ops>(r, edge2));
    terms.scaled_v = with_den_sign(kernel_dot<Ops>(r, edge1));
    terms.scaled_t = with_den_sign(kernel_dot<Ops>(terms.normal, to_v0));
    terms.abs_den = std::fabs(den);
    std::optional<EmbreeHitAttributes> hit = attributes_from_terms<Ops>(terms);
    if (!hit) return hit;
    // Our traversal's watertight test may accept a ray a rounding error outside this test's
    // edges; keep Embree's guarantee u, v >= 0 (the comparison keeps a -0 as Embree gives it).
    if (hit->u < 0.0f) hit->u = 0.0f;
    if (hit->v < 0.0f) hit->v = 0.0f;
    return hit;
}

}  // namespace

EmbreeKernelArithmetic detect_embree_kernel_arithmetic() {
#if defined(REBRAID_GLUE_HAS_RCP_ESTIMATES) && (defined(__GNUC__) || defined(__clang__))
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
        __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
        __builtin_cpu_supports("avx512vl"))
        return EmbreeKernelArithmetic::fused_rcp14;
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
        return EmbreeKernelArithmetic::fused;
#endif
    return EmbreeKernelArithmetic::separate;
}

AffineTransform embree_world_to_object(const AffineTransform& object_to_world) {
    // Embree inverts at commit in code built for the base instruction set: no fused
    // operations, whatever the kernels use. Measured bit for bit (dropin_results.md).
    auto plain_cross = [](Vec3f a, Vec3f b) -> Vec3f {
        return {rounded(a.y * b.z) - rounded(a.z * b.y), rounded(a.z * b.x) - rounded(a.x * b.z),
                rounded(a.x * b.y) - rounded(a.y * b.x)};
    };
    const AffineTransform& m = object_to_world;
    const Vec3f adjugate_row_x = plain_cross(m.col_y, m.col_z);
    const Vec3f adjugate_row_y = plain_cross(m.col_z, m.col_x);
    const Vec3f adjugate_row_z = plain_cross(m.col_x, m.col_y);
    const float det =
        (rounded(m.col_x.x * adjugate_row_x.x) + rounded(m.col_x.y * adjugate_row_x.y)) +
        rounded(m.col_x.z * adjugate_row_x.z);
    AffineTransform inverse;
    // Column j of the inverse holds component j of the adjugate's rows, each divided by det.
    for (int j = 0; j < 3; ++j) {
        const Vec3f column{adjugate_row_x[j] / det, adjugate_row_y[j] / det,
                           adjugate_row_z[j] / det};
        (j == 0 ? inverse.col_x : j == 1 ? inverse.col_y : inverse.col_z) = column;
    }
    const Vec3f& p = m.translation;
    for (int axis = 0; axis < 3; ++axis)
        inverse.translation[axis] =
            -(rounded(inverse.col_x[axis] * p.x) +
              (rounded(inverse.col_y[axis] * p.y) + rounded(inverse.col_z[axis] * p.z)));
    return inverse;
}

namespace {

/// hit_attributes<FusedRcp14Ops> compiled for AVX-512 as a whole (only called where the CPU
/// has it), so that the 14-bit estimate and every helper inline into one body.
#if defined(REBRAID_GLUE_HAS_RCP_ESTIMATES) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx512f"), flatten))
#endif
std::optional<EmbreeHitAttributes>
hit_attributes_rcp14(const Ray& world_ray, const AffineTransform* world_to_object,
                     const std::array<Vec3f, 3>& corners) {
    return hit_attributes<FusedRcp14Ops>(world_ray, world_to_object, corners);
}

}  // namespace

std::optional<EmbreeHitAttributes> embree_hit_attributes(const Ray& world_ray,
                                                         const AffineTransform* world_to_object,
                                                         const std::array<Vec3f, 3>& corners,
                                                         EmbreeKernelArithmetic arithmetic) {
    if (arithmetic == EmbreeKernelArithmetic::fused_rcp14)
        return hit_attributes_rcp14(world_ray, world_to_object, corners);
    if (arithmetic == EmbreeKernelArithmetic::fused)
        return hit_attributes<FusedOps>(world_ray, world_to_object, corners);
    return hit_attributes<SeparateOps>(world_ray, world_to_object, corners);
}

}  // namespace rebraid::glue
