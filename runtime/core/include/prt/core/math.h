// PointRT core: small vector math for host and device (float, the precision the GPU runs at).
// The host converts double-precision scene data (world positions, model origins) into the model's
// local frame before anything reaches these types, so float is enough here (DESIGN.md).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "prt/core/config.h"
#include "prt/formats/pool_layout.h"

namespace prt::core {

#if !PRT_DEVICE_CODE
/// Host: IEEE fminf / fmaxf (the other operand when one is NaN) written inline. Without
/// -ffinite-math-only g++ calls libm's for them (x86's minss / maxss keep a NaN second operand),
/// an out-of-line call in every walk step and leaf test of the CPU backend and the CPU culling (185
/// calls in prt-bench). Unqualified fminf / fmaxf in prt::core find these first; device code keeps
/// CUDA's (one instruction each).
inline float fminf(float a, float b) {
    return (b != b || a < b) ? a : b;
}
inline float fmaxf(float a, float b) {
    return (b != b || a > b) ? a : b;
}
#endif

inline constexpr float k_inf = std::numeric_limits<float>::infinity();

/// nextafterf(x, 0): the float next to x toward zero (+0 for +-0, as nextafterf gives its second
/// argument when the two are equal; NaN for NaN; FLT_MAX for inf). Written on the bits: the host
/// compiler calls libm for nextafterf, once per shadow ray.
PRT_HD PRT_INLINE float next_toward_zero(float x) {
    if (x == 0.0f) return 0.0f;
    if (x != x) return x;
    std::uint32_t b;
    memcpy(&b, &x, sizeof b);
    --b;  // magnitude one ulp smaller, sign kept: toward zero from either side (inf -> FLT_MAX)
    float r;
    memcpy(&r, &b, sizeof r);
    return r;
}
inline constexpr float k_pi = 3.14159265358979323846f;

/// A 3-vector of floats: points, directions, and linear RGB colors.
struct Vec3 {
    float x, y, z;
};

PRT_HD PRT_INLINE Vec3 vec3(float x, float y, float z) {
    return Vec3{x, y, z};
}
PRT_HD PRT_INLINE Vec3 vec3(float s) {
    return Vec3{s, s, s};
}
PRT_HD PRT_INLINE Vec3 vec3(const pool::Float3& f) {
    return Vec3{f.x, f.y, f.z};
}

PRT_HD PRT_INLINE Vec3 operator+(Vec3 a, Vec3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
PRT_HD PRT_INLINE Vec3 operator-(Vec3 a, Vec3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
PRT_HD PRT_INLINE Vec3 operator-(Vec3 a) {
    return {-a.x, -a.y, -a.z};
}
PRT_HD PRT_INLINE Vec3 operator*(Vec3 a, Vec3 b) {
    return {a.x * b.x, a.y * b.y, a.z * b.z};
}
PRT_HD PRT_INLINE Vec3 operator*(Vec3 a, float s) {
    return {a.x * s, a.y * s, a.z * s};
}
PRT_HD PRT_INLINE Vec3 operator*(float s, Vec3 a) {
    return {a.x * s, a.y * s, a.z * s};
}
PRT_HD PRT_INLINE Vec3 operator/(Vec3 a, float s) {
    return a * (1.0f / s);
}
PRT_HD PRT_INLINE Vec3& operator+=(Vec3& a, Vec3 b) {
    a = a + b;
    return a;
}
PRT_HD PRT_INLINE Vec3& operator*=(Vec3& a, float s) {
    a = a * s;
    return a;
}

PRT_HD PRT_INLINE float dot(Vec3 a, Vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
PRT_HD PRT_INLINE Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
PRT_HD PRT_INLINE float length2(Vec3 a) {
    return dot(a, a);
}
PRT_HD PRT_INLINE float length(Vec3 a) {
    return sqrtf(dot(a, a));
}
PRT_HD PRT_INLINE float min3(Vec3 a) {
    return fminf(a.x, fminf(a.y, a.z));
}
PRT_HD PRT_INLINE float max3(Vec3 a) {
    return fmaxf(a.x, fmaxf(a.y, a.z));
}
PRT_HD PRT_INLINE Vec3 vmin(Vec3 a, Vec3 b) {
    return {fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)};
}
PRT_HD PRT_INLINE Vec3 vmax(Vec3 a, Vec3 b) {
    return {fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)};
}
PRT_HD PRT_INLINE float clampf(float v, float lo, float hi) {
    return fminf(fmaxf(v, lo), hi);
}
PRT_HD PRT_INLINE Vec3 clamp(Vec3 a, float lo, float hi) {
    return {clampf(a.x, lo, hi), clampf(a.y, lo, hi), clampf(a.z, lo, hi)};
}
PRT_HD PRT_INLINE bool is_finite(float v) {
    return v - v == 0.0f;
}  // false for NaN and +-Inf
PRT_HD PRT_INLINE bool is_finite(Vec3 a) {
    return is_finite(a.x) && is_finite(a.y) && is_finite(a.z);
}

/// Unit vector along `a`, or `fallback` when `a` is zero or not finite (never NaN).
PRT_HD PRT_INLINE Vec3 normalize_or(Vec3 a, Vec3 fallback) {
    const float l2 = dot(a, a);
    if (!(l2 > 0.0f) || !is_finite(l2)) return fallback;
    return a * (1.0f / sqrtf(l2));
}
PRT_HD PRT_INLINE Vec3 normalize(Vec3 a) {
    return normalize_or(a, Vec3{0.0f, 0.0f, 1.0f});
}

/// Component `i` (0, 1, 2) of a vector.
PRT_HD PRT_INLINE float component(Vec3 a, int i) {
    return i == 0 ? a.x : (i == 1 ? a.y : a.z);
}
/// Sets component `i` (0, 1, 2) of a vector.
PRT_HD PRT_INLINE void set_component(Vec3& a, int i, float v) {
    if (i == 0)
        a.x = v;
    else if (i == 1)
        a.y = v;
    else
        a.z = v;
}

/// A 3x3 matrix stored by rows (rotations between a model's local frame and the render frame).
struct Mat3 {
    Vec3 r0, r1, r2;
};

PRT_HD PRT_INLINE Mat3 mat3_identity() {
    return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
}
PRT_HD PRT_INLINE Vec3 operator*(const Mat3& m, Vec3 v) {
    return {dot(m.r0, v), dot(m.r1, v), dot(m.r2, v)};
}
/// m^T v (the inverse of a rotation applied to v).
PRT_HD PRT_INLINE Vec3 mul_transpose(const Mat3& m, Vec3 v) {
    return m.r0 * v.x + m.r1 * v.y + m.r2 * v.z;
}

/// 2^-n as an exact float for 0 <= n <= 126 (built from the exponent bits, no rounding).
PRT_HD PRT_INLINE float exp2_neg(std::uint32_t n) {
    const std::uint32_t bits = (127u - n) << 23;
#if PRT_DEVICE_CODE
    return __uint_as_float(bits);
#else
    float f;
    static_assert(sizeof(f) == sizeof(bits));
    __builtin_memcpy(&f, &bits, sizeof(f));
    return f;
#endif
}

/// Reads a 32-byte pool element (Splat, MlsSplat, LeafBounds): on the GPU two 16-byte read-only
/// loads through the texture cache (pool payloads are 256-byte aligned, so 32-byte elements are
/// 16-byte aligned), on the host a plain copy.
template <class T>
PRT_HD PRT_INLINE T load_32_bytes(const T* p) {
    static_assert(sizeof(T) == 32, "load_32_bytes reads 32-byte elements");
#if PRT_DEVICE_CODE
    const float4 a = __ldg(reinterpret_cast<const float4*>(p));
    const float4 b = __ldg(reinterpret_cast<const float4*>(p) + 1);
    T s;
    memcpy(&s, &a, sizeof(a));
    memcpy(reinterpret_cast<char*>(&s) + sizeof(a), &b, sizeof(b));
    return s;
#else
    return *p;
#endif
}

}  // namespace prt::core
