#include "sim/urdf_robot.hpp"

#include "sim/urdf_model.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rise::sim {
namespace {

constexpr double kTol = 1e-6;
// The simulator's arm (sim/simulation_robots.cpp build_arm): a turret box on the
// chassis top, the upper arm rising 45° at zero angles, a fixed jaw and a
// finger of this size and mass.
constexpr std::array<double, 3> kTurretSize_m{0.14, 0.14, 0.08};
constexpr std::array<double, 3> kFingerSize_m{0.03, 0.02, 0.12};
constexpr double kFingerMass_kg = 0.3;
constexpr double kUpperRise_rad = M_PI / 4;

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

std::string text(const urdf::Vector3& v) {
  std::ostringstream s;
  s << v.x << " " << v.y << " " << v.z;
  return s.str();
}

bool near(const urdf::Vector3& v, double x, double y, double z) {
  return std::abs(v.x - x) < kTol && std::abs(v.y - y) < kTol && std::abs(v.z - z) < kTol;
}

void expect_near(double value, double want, const std::string& what) {
  if (std::abs(value - want) > kTol)
    fail(what + " is " + std::to_string(value) + ", the simulator's model needs " + std::to_string(want));
}

void expect_origin(const urdf::Pose& p, const std::string& what, double x, double y, double z, double pitch_rad) {
  double roll = 0, pitch = 0, yaw = 0;
  p.rotation.getRPY(roll, pitch, yaw);
  if (!near(p.position, x, y, z))
    fail(what + " origin xyz is " + text(p.position) + ", the simulator's model needs " +
         text(urdf::Vector3(x, y, z)));
  if (std::abs(roll) > kTol || std::abs(pitch - pitch_rad) > kTol || std::abs(yaw) > kTol)
    fail(what + " origin rpy is " + text(urdf::Vector3(roll, pitch, yaw)) + ", the simulator's model needs " +
         text(urdf::Vector3(0, pitch_rad, 0)));
}

const char* shape_name(int type) {
  switch (type) {
    case urdf::Geometry::SPHERE: return "sphere";
    case urdf::Geometry::BOX: return "box";
    case urdf::Geometry::CYLINDER: return "cylinder";
    default: return "mesh";
  }
}

urdf::LinkConstSharedPtr link_of(const urdf::ModelInterface& m, const std::string& name) {
  auto l = m.getLink(name);
  if (!l) fail("no link '" + name + "'");
  return l;
}

/// The link's only collision shape (`index` of `count`), checked to be `want`.
const urdf::Collision& collision(const urdf::Link& l, int want, std::size_t index = 0, std::size_t count = 1) {
  if (l.collision_array.size() != count)
    fail("link '" + l.name + "' has " + std::to_string(l.collision_array.size()) + " collision shapes, expected " +
         std::to_string(count));
  const urdf::Collision& c = *l.collision_array[index];
  if (!c.geometry) fail("link '" + l.name + "' has a collision without geometry");
  if (c.geometry->type != want)
    fail("link '" + l.name + "': unsupported collision shape " + std::string(shape_name(c.geometry->type)) +
         " (the simulator needs a " + shape_name(want) + ")");
  // liburdfdom takes any number; a body of negative or zero size is none.
  bool sized = true;
  if (want == urdf::Geometry::BOX) {
    const auto& d = static_cast<const urdf::Box&>(*c.geometry).dim;
    sized = d.x > 0 && d.y > 0 && d.z > 0;
  } else if (want == urdf::Geometry::CYLINDER) {
    const auto& cyl = static_cast<const urdf::Cylinder&>(*c.geometry);
    sized = cyl.radius > 0 && cyl.length > 0;
  }
  if (!sized) fail("link '" + l.name + "': the " + shape_name(want) + "'s sizes must be > 0");
  return c;
}

std::array<double, 3> box_size(const urdf::Collision& c) {
  const auto& b = static_cast<const urdf::Box&>(*c.geometry);
  return {b.dim.x, b.dim.y, b.dim.z};
}

/// The link's mass; its inertia must be that of the solid shape (trace
/// within 1 %, rotation-free), which is what the simulator uses.
double mass_of(const urdf::Link& l, double trace_kgm2_per_kg) {
  if (!l.inertial) fail("link '" + l.name + "' has no inertial");
  const urdf::Inertial& i = *l.inertial;
  if (!(i.mass > 0 && std::isfinite(i.mass))) fail("link '" + l.name + "': mass must be > 0");
  const double want = i.mass * trace_kgm2_per_kg;
  const double trace = i.ixx + i.iyy + i.izz;
  if (std::abs(trace - want) > 0.01 * want)
    fail("link '" + l.name + "': inertia ixx+iyy+izz = " + std::to_string(trace) + " kg m^2 is not the solid " +
         "shape's " + std::to_string(want) + " (the simulator computes inertia from the collision shape)");
  return i.mass;
}

double box_trace_per_kg(const std::array<double, 3>& s) {
  return (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) / 6.0;  // (1/12)·2·(x²+y²+z²)
}

urdf::JointConstSharedPtr joint_of(const urdf::ModelInterface& m, const std::string& name, int type,
                                   const char* type_name, const std::string& parent) {
  auto j = m.getJoint(name);
  if (!j) fail("no joint '" + name + "'");
  if (j->type != type) fail("joint '" + name + "' must be " + type_name);
  if (j->parent_link_name != parent)
    fail("joint '" + name + "' has parent '" + j->parent_link_name + "', expected '" + parent + "'");
  return j;
}

void expect_axis(const urdf::Joint& j, double x, double y, double z) {
  if (!near(j.axis, x, y, z))
    fail("joint '" + j.name + "' axis is " + text(j.axis) + ", the simulator's model needs " +
         text(urdf::Vector3(x, y, z)));
}

void read_wheels(const urdf::ModelInterface& m, const std::string& base, const std::array<std::string, 4>& names,
                 double chassis_h_m, UrdfRobot& out) {
  WheelsDescription w;
  std::array<urdf::Vector3, 4> at{};
  for (std::size_t i = 0; i < 4; ++i) {
    const auto j = joint_of(m, names[i], urdf::Joint::CONTINUOUS, "continuous", base);
    expect_axis(*j, 0, 1, 0);
    const auto l = link_of(m, j->child_link_name);
    const urdf::Collision& c = collision(*l, urdf::Geometry::CYLINDER);
    const auto& cyl = static_cast<const urdf::Cylinder&>(*c.geometry);
    // URDF cylinders lie along their z axis; the wheel's must lie along y.
    const urdf::Vector3 axis = c.origin.rotation * urdf::Vector3(0, 0, 1);
    if (!near(c.origin.position, 0, 0, 0) || std::abs(std::abs(axis.y) - 1.0) > kTol)
      fail("link '" + l->name + "': the wheel cylinder must be centred on the joint with its axis along y");
    const double r2 = cyl.radius * cyl.radius;
    const double mass = mass_of(*l, r2 / 2 + 2 * (3 * r2 + cyl.length * cyl.length) / 12);  // axis + 2 × across
    if (i == 0) {
      w.radius_m = cyl.radius;
      w.width_m = cyl.length;
      w.mass_kg = mass;
    } else {
      expect_near(cyl.radius, w.radius_m, "link '" + l->name + "' radius");
      expect_near(cyl.length, w.width_m, "link '" + l->name + "' length");
      expect_near(mass, w.mass_kg, "link '" + l->name + "' mass");
    }
    at[i] = j->parent_to_joint_origin_transform.position;
  }
  // The simulator's wheels sit at (±wheelbase/2, ±track/2), all at one height.
  w.wheelbase_m = at[0].x - at[2].x;
  w.track_m = at[0].y - at[1].y;
  for (std::size_t i = 0; i < 4; ++i) {
    const double x = i < 2 ? w.wheelbase_m / 2 : -w.wheelbase_m / 2;
    const double y = i % 2 == 0 ? w.track_m / 2 : -w.track_m / 2;
    if (!near(at[i], x, y, at[0].z))
      fail("joint '" + names[i] + "' origin xyz is " + text(at[i]) + ": the wheels must sit at (±wheelbase/2, " +
           "±track/2) at one height, in the order front left, front right, rear left, rear right");
  }
  if (!(w.wheelbase_m > 0 && w.track_m > 0)) fail("the wheels must be front left, front right, rear left, rear right");
  out.clearance_m = w.radius_m - at[0].z - chassis_h_m / 2;
  if (!(*out.clearance_m >= 0)) fail("the wheel joints put the chassis bottom below the ground");
  out.wheels = w;
}

void read_arm(const urdf::ModelInterface& m, const std::string& base, const std::array<std::string, 4>& names,
              double chassis_h_m, UrdfRobot& out) {
  ArmDescription a;
  const auto yaw = joint_of(m, names[0], urdf::Joint::REVOLUTE, "revolute", base);
  expect_axis(*yaw, 0, 0, 1);
  const auto& p0 = yaw->parent_to_joint_origin_transform;
  expect_origin(p0, "joint '" + yaw->name + "'", p0.position.x, p0.position.y, chassis_h_m / 2, 0.0);
  a.mount_m = {p0.position.x, p0.position.y};
  const auto turret = link_of(m, yaw->child_link_name);
  const urdf::Collision& tc = collision(*turret, urdf::Geometry::BOX);
  const auto ts = box_size(tc);
  for (std::size_t i = 0; i < 3; ++i) expect_near(ts[i], kTurretSize_m[i], "link '" + turret->name + "' box size");
  expect_origin(tc.origin, "link '" + turret->name + "' collision", 0, 0, kTurretSize_m[2] / 2, 0.0);
  a.link_mass_kg = mass_of(*turret, box_trace_per_kg(ts));

  const auto pitch = joint_of(m, names[1], urdf::Joint::REVOLUTE, "revolute", turret->name);
  expect_axis(*pitch, 0, -1, 0);
  expect_origin(pitch->parent_to_joint_origin_transform, "joint '" + pitch->name + "'", 0, 0, kTurretSize_m[2],
                -kUpperRise_rad);
  const auto upper = link_of(m, pitch->child_link_name);
  const urdf::Collision& uc = collision(*upper, urdf::Geometry::BOX);
  const auto us = box_size(uc);
  a.upper_length_m = us[0];
  a.link_width_m = us[1];
  expect_near(us[2], us[1], "link '" + upper->name + "' box height (links are square)");
  expect_origin(uc.origin, "link '" + upper->name + "' collision", us[0] / 2, 0, 0, 0.0);
  expect_near(mass_of(*upper, box_trace_per_kg(us)), a.link_mass_kg, "link '" + upper->name + "' mass (one for all links)");

  const auto elbow = joint_of(m, names[2], urdf::Joint::REVOLUTE, "revolute", upper->name);
  expect_axis(*elbow, 0, -1, 0);
  expect_origin(elbow->parent_to_joint_origin_transform, "joint '" + elbow->name + "'", a.upper_length_m, 0, 0,
                kUpperRise_rad);
  const auto fore = link_of(m, elbow->child_link_name);
  // The forearm's first collision is the link, its second the fixed jaw.
  const urdf::Collision& fc = collision(*fore, urdf::Geometry::BOX, 0, 2);
  const auto fs = box_size(fc);
  a.forearm_length_m = fs[0];
  expect_near(fs[1], a.link_width_m, "link '" + fore->name + "' box width");
  expect_near(fs[2], a.link_width_m, "link '" + fore->name + "' box height");
  expect_origin(fc.origin, "link '" + fore->name + "' collision", fs[0] / 2, 0, 0, 0.0);
  expect_near(mass_of(*fore, box_trace_per_kg(fs)), a.link_mass_kg, "link '" + fore->name + "' mass (one for all links)");

  const auto grip = joint_of(m, names[3], urdf::Joint::PRISMATIC, "prismatic", fore->name);
  expect_axis(*grip, 0, 1, 0);
  if (!grip->limits || std::abs(grip->limits->upper) > kTol || !(grip->limits->lower < 0))
    fail("joint '" + grip->name + "' limits must be lower = -stroke, upper = 0 (0 = open)");
  a.gripper_stroke_m = -grip->limits->lower;
  const urdf::Collision& jaw = collision(*fore, urdf::Geometry::BOX, 1, 2);
  const auto js = box_size(jaw);
  for (std::size_t i = 0; i < 3; ++i) expect_near(js[i], kFingerSize_m[i], "link '" + fore->name + "' jaw box size");
  expect_origin(jaw.origin, "link '" + fore->name + "' jaw collision", a.forearm_length_m, -a.gripper_stroke_m / 2,
                -kFingerSize_m[2] / 2, 0.0);
  expect_origin(grip->parent_to_joint_origin_transform, "joint '" + grip->name + "'", a.forearm_length_m,
                a.gripper_stroke_m / 2, -kFingerSize_m[2] / 2, 0.0);
  const auto finger = link_of(m, grip->child_link_name);
  const urdf::Collision& gc = collision(*finger, urdf::Geometry::BOX);
  const auto gs = box_size(gc);
  for (std::size_t i = 0; i < 3; ++i) expect_near(gs[i], kFingerSize_m[i], "link '" + finger->name + "' box size");
  expect_origin(gc.origin, "link '" + finger->name + "' collision", 0, 0, 0, 0.0);
  expect_near(mass_of(*finger, box_trace_per_kg(gs)), kFingerMass_kg, "link '" + finger->name + "' mass");

  for (std::size_t i = 0; i < 3; ++i) {
    const auto j = m.getJoint(names[i]);
    const double lo = j->limits->lower, hi = j->limits->upper;
    if (!(lo < 0.0 && hi > 0.0)) fail("joint '" + j->name + "' limits must include 0 (lower < 0 < upper)");
    out.arm_limits_rad[i] = {lo, hi};
  }
  out.arm = a;
}

}  // namespace

UrdfRobot read_urdf_robot(const std::string& path, const UrdfJointNames& joints) {
  // liburdfdom says only "does not exist", also for a file it may not read.
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  return parse_urdf_robot(text.str(), joints);
}

UrdfRobot parse_urdf_robot(const std::string& xml, const UrdfJointNames& joints) {
  const urdf::ModelInterfaceSharedPtr model = parse_urdf_model(xml);
  const auto root = model->getRoot();
  if (!root) fail("no root link");
  UrdfRobot out;
  const urdf::Collision& c = collision(*root, urdf::Geometry::BOX);
  expect_origin(c.origin, "link '" + root->name + "' collision", 0, 0, 0, 0.0);
  out.chassis_size_m = box_size(c);
  out.chassis_mass_kg = mass_of(*root, box_trace_per_kg(out.chassis_size_m));
  if (joints.wheels) read_wheels(*model, root->name, *joints.wheels, out.chassis_size_m[2], out);
  if (joints.arm) read_arm(*model, root->name, *joints.arm, out.chassis_size_m[2], out);
  return out;
}

}  // namespace rise::sim
