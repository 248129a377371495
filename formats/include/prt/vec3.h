// PointRT: the 3-vector of host code (scene positions and directions in double, world units) and its
// arithmetic, shared by every host-side tool and library (synth, import, the runtime's host side,
// the benches, the scene description).
//
// Why std::array and not the core's Vec3: the device-side vector (prt/core/math.h, float, PRT_HD) is
// the type every kernel is written in; host code keeps double precision until it converts into a
// model's local frame (DESIGN.md), and its vectors are std::array<double, 3> everywhere: the scene
// description (prt/formats/scene.h), JSON (nlohmann converts std::array), provenance, indexing by
// axis. Free functions over Vec3T<T> = std::array<T, 3> give those the one arithmetic they had six
// copies of, with the same operations in the same order (results unchanged to the bit), and no
// conversion at any boundary. Host only.
#pragma once

#include <array>
#include <cmath>
#include <type_traits>

namespace prt {

/// A host 3-vector of T (x, y, z by index).
template <class T>
using Vec3T = std::array<T, 3>;
/// The double vector of host code.
using Vec3d = Vec3T<double>;

// The second operand is a non-deduced context: {x, y, z} and plain numbers convert to it.
template <class T>
constexpr Vec3T<T> add(const Vec3T<T>& a, const std::type_identity_t<Vec3T<T>>& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
template <class T>
constexpr Vec3T<T> sub(const Vec3T<T>& a, const std::type_identity_t<Vec3T<T>>& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
/// a * s.
template <class T>
constexpr Vec3T<T> mul(const Vec3T<T>& a, std::type_identity_t<T> s) {
    return {a[0] * s, a[1] * s, a[2] * s};
}
template <class T>
constexpr T dot(const Vec3T<T>& a, const std::type_identity_t<Vec3T<T>>& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
template <class T>
constexpr Vec3T<T> cross(const Vec3T<T>& a, const std::type_identity_t<Vec3T<T>>& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
/// Euclidean length, sqrt(dot(a, a)).
template <class T>
T length(const Vec3T<T>& a) {
    return std::sqrt(dot(a, a));
}
/// a / |a|, or the zero vector when |a| is 0.
template <class T>
Vec3T<T> normalized(const Vec3T<T>& a) {
    const T l = length(a);
    return l > 0 ? mul(a, T(1) / l) : Vec3T<T>{0, 0, 0};
}

}  // namespace prt
