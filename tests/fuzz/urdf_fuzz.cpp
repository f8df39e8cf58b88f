// libFuzzer target: a robot's URDF alone (sim/urdf_robot.hpp): liburdfdom's
// parser on the text, then our checks on its tree, with the joints the
// first byte picks (none, skid4's wheels, tracked_eod's arm, both). An
// error must be a std::runtime_error; what is taken must be a body the
// simulator can build: every size, mass and distance finite and > 0 (the
// clearance >= 0), the arm's limits around 0.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "sim/urdf_robot.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace sim = rise::sim;

namespace {

bool positive(double v) { return std::isfinite(v) && v > 0; }

void check_robot(const sim::UrdfRobot& u, const sim::UrdfJointNames& joints) {
  for (double s : u.chassis_size_m) fuzz_check(positive(s));
  fuzz_check(positive(u.chassis_mass_kg));
  fuzz_check(u.wheels.has_value() == joints.wheels.has_value());
  fuzz_check(u.arm.has_value() == joints.arm.has_value());
  if (u.wheels) {
    const auto& w = *u.wheels;
    fuzz_check(positive(w.radius_m) && positive(w.width_m) && positive(w.mass_kg));
    fuzz_check(positive(w.wheelbase_m) && positive(w.track_m));
    fuzz_check(u.clearance_m && std::isfinite(*u.clearance_m) && *u.clearance_m >= 0);
  }
  if (u.arm) {
    const auto& a = *u.arm;
    fuzz_check(std::isfinite(a.mount_m[0]) && std::isfinite(a.mount_m[1]));
    fuzz_check(positive(a.upper_length_m) && positive(a.forearm_length_m) && positive(a.link_width_m));
    fuzz_check(positive(a.link_mass_kg) && positive(a.gripper_stroke_m));
    for (const auto& [lo, hi] : u.arm_limits_rad) fuzz_check(std::isfinite(lo) && std::isfinite(hi) && lo < 0 && hi > 0);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string xml(reinterpret_cast<const char*>(data) + 1, size - 1);
  sim::UrdfJointNames joints;
  if (data[0] & 1)
    joints.wheels = {"front_left_wheel_joint", "front_right_wheel_joint", "rear_left_wheel_joint", "rear_right_wheel_joint"};
  if (data[0] & 2) joints.arm = {"shoulder_yaw", "shoulder_pitch", "elbow_pitch", "gripper"};
  try {
    check_robot(sim::parse_urdf_robot(xml, joints), joints);
  } catch (const std::runtime_error& e) {
    fuzz_check(e.what()[0] != '\0');
  }
  return 0;
}
