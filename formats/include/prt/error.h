// PointRT: the one error type host code throws. `main` catches it at the boundary, prints one line
// naming the file and what is wrong, and exits non-zero (see prt/cli.h).
#pragma once

#include <stdexcept>
#include <string>

namespace prt {

/// A runtime error a user can act on: the message names the file (or JSON path) and what is wrong.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Exit codes shared by every tool: usage errors apart from runtime errors (instant-ngp style).
inline constexpr int k_exit_ok = 0;
inline constexpr int k_exit_runtime_error = 1;
inline constexpr int k_exit_usage_error = 2;

}  // namespace prt
