// libFuzzer target: a robot's URDF alone (sim/urdf_robot.hpp): liburdfdom's
// parser on the text, then our checks on its tree, with the joints the
// first byte picks (none, skid4's wheels, tracked_eod's arm, both). An
// error must be a std::runtime_error; what is taken must be a body the
// simulator can build: every size, mass and distance finite and > 0 (the
// clearance >= 0), the arm's limits around 0. With bit 2 of the first byte
// the general tree (sim/urdf_tree.hpp, meshes by name only): a tree whose
// joints lead to the links after the root, parents first, every number
// finite, axes unit, limits ordered, and a mass on every body.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/urdf_robot.hpp"
#include "sim/urdf_tree.hpp"
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

bool finite_pose(const sim::UrdfPose& p) {
  for (double v : p.xyz_m)
    if (!std::isfinite(v)) return false;
  double n = 0;
  for (double v : p.wxyz) n += v * v;
  return std::fabs(n - 1.0) < 1e-6;
}

void check_tree(const sim::UrdfTree& t) {
  fuzz_check(!t.links.empty() && t.links.size() <= sim::kMaxUrdfLinks);
  fuzz_check(t.joints.size() + 1 == t.links.size());
  for (std::size_t i = 0; i < t.joints.size(); ++i) {
    const auto& j = t.joints[i];
    fuzz_check(j.child == i + 1 && j.parent < j.child);
    fuzz_check(finite_pose(j.origin));
    if (j.type != sim::UrdfJointType::Fixed) {
      fuzz_check(std::fabs(j.axis[0] * j.axis[0] + j.axis[1] * j.axis[1] + j.axis[2] * j.axis[2] - 1.0) < 1e-9);
      fuzz_check(positive(t.links[j.child].mass_kg));
    }
    fuzz_check(std::isfinite(j.lower) && std::isfinite(j.upper) && j.lower <= j.upper);
    fuzz_check(j.effort >= 0 && j.velocity >= 0 && j.damping >= 0 && j.friction >= 0);
  }
  std::vector<double> body_mass(t.links.size(), 0.0);
  for (std::size_t l = 0; l < t.links.size(); ++l) {
    const auto& link = t.links[l];
    fuzz_check(link.mass_kg == 0.0 || (positive(link.mass_kg) && finite_pose(link.inertial_origin)));
    for (const auto* shapes : {&link.collisions, &link.visuals})
      for (const auto& s : *shapes) {
        fuzz_check(finite_pose(s.origin));
        for (double v : s.size_m) fuzz_check(positive(v));
        fuzz_check(s.mesh.triangles.empty());  // meshes are not read here
      }
    const std::size_t b = t.body_link(l);
    fuzz_check(b <= l);
    body_mass[b] += link.mass_kg;
  }
  for (std::size_t l = 0; l < t.links.size(); ++l)
    if (t.body_link(l) == l) fuzz_check(positive(body_mass[l]));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string xml(reinterpret_cast<const char*>(data) + 1, size - 1);
  if (data[0] & 4) {
    try {
      check_tree(sim::parse_urdf_tree(xml, "", false));
    } catch (const std::runtime_error& e) {
      fuzz_check(e.what()[0] != '\0');
    }
    return 0;
  }
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
