// PointRT player: camera motion for headless runs: an orbit about the look-at point, or a camera
// path file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "prt/formats/scene.h"

namespace prt::player {

/// One key of a camera path (world frame).
struct CameraKey {
    scene::Vec3 position;
    scene::Vec3 look_at;
    double fov_y_degrees = 0;  ///< 0: keep the scene camera's
};

/// Reads a camera path file: one key per line, "px py pz lx ly lz [fov_y_degrees]", '#' starts a
/// comment, blank lines are skipped. Throws prt::Error "FILE:LINE: what" on bad input or no keys.
std::vector<CameraKey> read_camera_path(const std::filesystem::path& file);

/// The camera of frame `frame`: `base` rotated about its up direction (the +y axis for the
/// default up) through its look-at point by frame * degrees_per_frame (an orbit; 0 keeps it still).
scene::Camera orbit_camera(const scene::Camera& base, std::uint32_t frame, double degrees_per_frame);

/// The camera of frame `frame` along a path (frames cycle through the keys).
scene::Camera path_camera(const scene::Camera& base, const std::vector<CameraKey>& path, std::uint32_t frame);

}  // namespace prt::player
