// libFuzzer target: 3DTK's .3d scan, .pose and .frames readers and the
// simulator's .pose reader on arbitrary text. An error must be a
// std::runtime_error whose text starts with "file:"; points must be finite
// and every pose read a rotation (orthonormal, determinant +1).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string_view>

#include "semantic/cloud_formats.hpp"

namespace fmt = rise::semantic::formats;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

void check_pose(const Eigen::Isometry3d& T) {
  if (!T.matrix().allFinite()) return;  // huge angles or positions may overflow; never a crash
  const Eigen::Matrix3d R = T.linear();
  check((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6);
  check(std::abs(R.determinant() - 1.0) < 1e-6);
}

template <typename F>
void expect_clean(const char* name, F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with(name) && e.what()[std::string_view(name).size()] == ':');
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  expect_clean("fuzz.3d", [&] {
    for (const auto& p : fmt::parse_3d("fuzz.3d", text).points) check(p.allFinite());
  });
  expect_clean("fuzz.pose", [&] { check_pose(fmt::parse_3dtk_pose("fuzz.pose", text)); });
  expect_clean("fuzz.frames", [&] {
    for (const auto& T : fmt::parse_3dtk_frames("fuzz.frames", text)) check_pose(T);
  });
  expect_clean("sim.pose", [&] { check_pose(fmt::parse_sim_pose("sim.pose", text)); });
  return 0;
}
