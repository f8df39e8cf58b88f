#include "sim/simulation.hpp"

#include <ode/ode.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdarg>
#include <mutex>
#include <set>
#include <stdexcept>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

std::atomic<int64_t> g_ode_messages{0};

// ODE reports solver hiccups ("LCP internal error") as messages on stderr;
// a library does not print, so they are counted instead (ode_messages()).
void count_message(int, const char*, va_list) { ++g_ode_messages; }

void init_ode_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    dInitODE2(0);
    dRandSetSeed(0);
    dSetMessageHandler(&count_message);
  });
}

}  // namespace

int64_t ode_messages() { return g_ode_messages.load(); }

double RobotSnapshot::yaw_rad() const {
  const auto& q = orientation_wxyz;
  return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
}

double RobotSnapshot::speed_mps() const { return std::hypot(linear_velocity_mps[0], linear_velocity_mps[1]); }

void Simulation::Impl::build(std::vector<RobotSpec> specs) {
  add_robots(std::move(specs));
  create_ode_world();
  // Feedback pointers into breakables must stay valid.
  std::size_t robot_joints = 0;
  for (const auto& r : robots) robot_joints += 8 + (r->desc.tree ? r->desc.tree->joints.size() : 0);
  breakables.reserve(world_desc.doors.size() + robot_joints);

  build_world();
  for (std::size_t i = 0; i < robots.size(); ++i) {
    Robot& r = *robots[i];
    build_robot(r, static_cast<int>(i));
    // Separate noise streams, so that one sensor's draws never shift
    // another's, nor one robot's another robot's (the first robot's
    // streams are those of a one-robot world).
    const uint64_t seed = r.desc.sensors.seed + 0x9E3779B97F4A7C15ull * static_cast<uint64_t>(i);
    // A urdf_tree's odometry reads the base's own motion (side_speeds_mps) with a 1 m gauge.
    const double gauge = r.desc.kind == RobotKind::Tracked  ? r.desc.tracks.gauge_m
                         : r.desc.kind == RobotKind::UrdfTree ? 1.0
                                                              : r.desc.wheels.track_m;
    r.odometry.emplace(r.desc.sensors.odometry, gauge, r.start.xy_m, r.start.yaw_rad, seed * 2 + 1);
    r.imu.emplace(r.desc.sensors.imu, Eigen::Vector3d(0, 0, -9.81), seed * 2 + 2);
  }
  ray = dCreateRay(nullptr, 1.0);
  dGeomRaySetClosestHit(ray, 1);
}

// The robots with their ids and start poses (not yet their bodies).
void Simulation::Impl::add_robots(std::vector<RobotSpec> specs) {
  if (specs.empty()) throw std::invalid_argument("simulation: no robots");
  std::set<std::string> ids;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    auto& spec = specs[i];
    if (spec.id.empty() || spec.id.find('/') != std::string::npos)
      throw std::invalid_argument("simulation: robot " + std::to_string(i) + ": bad id '" + spec.id +
                                  "' (needs one, without '/')");
    if (!ids.insert(spec.id).second) throw std::invalid_argument("simulation: robot id '" + spec.id + "' twice");
    auto r = std::make_unique<Robot>();
    r->id = spec.id;
    r->desc = std::move(spec.description);
    if (spec.start) {
      r->start = *spec.start;
    } else if (i == 0) {
      r->start = RobotStart{world_desc.robot_start_m, world_desc.robot_start_yaw_rad};
    } else if (i - 1 < world_desc.robot_starts.size()) {
      r->start = world_desc.robot_starts[i - 1];
    } else {
      throw std::invalid_argument("simulation: robot '" + spec.id + "': no start pose (the world has robot_start and " +
                                  std::to_string(world_desc.robot_starts.size()) + " robot_starts)");
    }
    for (const auto& c : r->desc.sounds) r->button_cues = r->button_cues || c.trigger == SoundTrigger::Button;
    robots.push_back(std::move(r));
  }
}

void Simulation::Impl::create_ode_world() {
  init_ode_once();
  world = dWorldCreate();
  dWorldSetGravity(world, 0, 0, -9.81);
  dWorldSetERP(world, 0.2);
  dWorldSetCFM(world, 1e-5);
  dWorldSetContactSurfaceLayer(world, 0.0005);
  dWorldSetAutoDisableFlag(world, 0);
  // Simple spaces keep the collision order independent of memory
  // addresses: the same inputs give the same contacts, step for step.
  // What never moves has its own space, so static pairs are never tested.
  space = dSimpleSpaceCreate(nullptr);
  static_space = dSimpleSpaceCreate(nullptr);
  contacts = dJointGroupCreate(0);
}

void Simulation::Impl::build_robot(Robot& r, int index) {
  if (r.desc.kind == RobotKind::UrdfTree) {
    build_urdf_tree(r, index);
    place_robot(r);
    return;
  }
  if (r.desc.kind == RobotKind::Tracked) build_tracked(r, index);
  else build_skid_steer(r, index);
  if (r.desc.arm && r.desc.control.arm) build_arm(r, index);
  place_robot(r);
}

void Simulation::Impl::step() {
  for (std::size_t i = 0; i < robots.size(); ++i)
    if (!robots[i]->faults.empty()) clear_fault(i, {}, "ended");
  for (auto& r : robots) {
    apply_command(*r);
    r->touching.clear();
  }
  seen.clear();
  dSpaceCollide(space, this, &near_callback);
  dSpaceCollide2(reinterpret_cast<dGeomID>(space), reinterpret_cast<dGeomID>(static_space), this, &near_callback);
  apply_door_return_torques();
  dWorldStep(world, kStepS);
  dJointGroupEmpty(contacts);
  ++steps;
  for (auto& rp : robots) {
    Robot& r = *rp;
    for (std::size_t i = 0; i < 2; ++i) r.track_travel_m[i] += r.track_speed_mps[i] * kStepS;
    update_arm_efforts(r);
    if (!r.tree_joints.empty()) unwrap_tree_joints(r);
    update_sensors(r);
  }
  check_breakables();
  update_events();
}

Simulation::Impl::~Impl() {
  if (ray) dGeomDestroy(ray);
  if (contacts) dJointGroupDestroy(contacts);
  if (space) dSpaceDestroy(space);
  for (auto& r : robots)
    for (dTriMeshDataID d : r->trimeshes) dGeomTriMeshDataDestroy(d);
  if (static_space) dSpaceDestroy(static_space);
  if (world) dWorldDestroy(world);
}

// Tracks as their end rollers: angle and rate of a roller of the track's
// radius; wheels with the motor torque on them.
std::vector<WheelState> Simulation::Impl::wheel_states(const Robot& s) {
  std::vector<WheelState> wheels;
  if (s.desc.kind == RobotKind::UrdfTree) return wheels;  // its wheels are joints
  if (s.desc.kind == RobotKind::Tracked) {
    const double radius = s.desc.tracks.radius_m;
    for (std::size_t i = 0; i < 2; ++i)
      wheels.push_back(WheelState{kTrackNames[i], s.track_travel_m[i] / radius, s.track_speed_mps[i] / radius, 0.0});
    return wheels;
  }
  for (std::size_t i = 0; i < 4; ++i) {
    WheelState ws;
    ws.name = kWheelNames[i];
    ws.position_rad = dJointGetHingeAngle(s.hinges[i]);
    ws.velocity_radps = dJointGetHingeAngleRate(s.hinges[i]);
    dVector3 axis;
    dJointGetHingeAxis(s.hinges[i], axis);
    const auto& t = s.feedback[i].t2;  // torque on the wheel from the hinge
    ws.effort_nm = t[0] * axis[0] + t[1] * axis[1] + t[2] * axis[2];
    wheels.push_back(ws);
  }
  return wheels;
}

std::vector<JointState> Simulation::Impl::joint_states(const Robot& s) const {
  std::vector<JointState> joints;
  for (std::size_t i = 0; i < s.arm_joints.size(); ++i) {
    const auto& a = s.arm_joints[i];
    JointState j;
    j.name = breakables[a.breakable].name;
    j.broken = a.joint == nullptr;
    if (!j.broken) {
      j.position = a.slider ? dJointGetSliderPosition(a.joint) : dJointGetHingeAngle(a.joint);
      j.velocity = a.slider ? dJointGetSliderPositionRate(a.joint) : dJointGetHingeAngleRate(a.joint);
      j.effort = s.arm_efforts[i];
      if (i < s.tree_joints.size() && s.tree_joints[i].continuous) j.position = s.tree_joints[i].turned_rad;
    }
    joints.push_back(j);
  }
  return joints;
}

Simulation::Simulation(RobotDescription robot, WorldDescription world) : impl_(std::make_unique<Impl>()) {
  std::vector<RobotSpec> specs(1);
  specs[0].id = robot.name.empty() ? "robot" : robot.name;
  specs[0].description = std::move(robot);
  impl_->world_desc = std::move(world);
  impl_->build(std::move(specs));
}

Simulation::Simulation(std::vector<RobotSpec> robots, WorldDescription world) : impl_(std::make_unique<Impl>()) {
  impl_->world_desc = std::move(world);
  impl_->build(std::move(robots));
}

Simulation::~Simulation() = default;

std::size_t Simulation::robot_count() const { return impl_->robots.size(); }
const std::string& Simulation::robot_id(std::size_t robot) const { return impl_->robots.at(robot)->id; }
std::size_t Simulation::robot_index(const std::string& id) const {
  for (std::size_t i = 0; i < impl_->robots.size(); ++i)
    if (impl_->robots[i]->id == id) return i;
  throw std::out_of_range("simulation: no robot '" + id + "'");
}

void Simulation::set_input(const ControlInput& input) { impl_->robots.front()->input = input; }
void Simulation::set_input(std::size_t robot, const ControlInput& input) {
  if (robot < impl_->robots.size()) impl_->robots[robot]->input = input;
}
void Simulation::step() { impl_->step(); }
double Simulation::time_s() const { return impl_->time_s(); }
const RobotDescription& Simulation::robot() const { return impl_->robots.front()->desc; }
const RobotDescription& Simulation::robot(std::size_t robot) const { return impl_->robots.at(robot)->desc; }

RobotSnapshot Simulation::snapshot() const { return snapshot(0); }

RobotSnapshot Simulation::snapshot(std::size_t robot) const {
  const Impl::Robot& s = *impl_->robots.at(robot);
  RobotSnapshot r;
  r.time_s = time_s();
  for (const auto& f : s.faults) r.active_faults.push_back(f.id + ": " + to_string(f.kind) + " " + f.target);
  const dReal* q = dBodyGetQuaternion(s.chassis);
  const Eigen::Vector3d p = Impl::T_world_base(s).translation();
  r.position_m = {p[0], p[1], p[2]};
  r.orientation_wxyz = {q[0], q[1], q[2], q[3]};
  dVector3 v, w;
  const dReal* lv = dBodyGetLinearVel(s.chassis);
  const dReal* av = dBodyGetAngularVel(s.chassis);
  dBodyVectorFromWorld(s.chassis, lv[0], lv[1], lv[2], v);
  dBodyVectorFromWorld(s.chassis, av[0], av[1], av[2], w);
  r.linear_velocity_mps = {v[0], v[1], v[2]};
  r.angular_velocity_radps = {w[0], w[1], w[2]};
  r.wheels = Impl::wheel_states(s);
  r.joints = impl_->joint_states(s);
  if (s.finger) {
    const dReal* f = dBodyGetPosition(s.finger);
    r.gripper_position_m = {f[0], f[1], f[2]};
  }
  r.contacts.assign(s.touching.begin(), s.touching.end());
  r.damage = s.damage;
  r.arm_enabled = s.arm_command.enabled;
  r.motors_enabled = s.command.enabled;
  r.stop_reason = s.command.stop_reason;
  r.commanded_linear_mps = s.command.linear_mps;
  r.commanded_angular_radps = s.command.angular_radps;
  r.odometry = s.odometry->reading();
  r.imu = s.imu->reading();
  r.sounds = Impl::continuous_cues(s, r.time_s);
  return r;
}

double stop_time_s(const RobotDescription& robot, double speed_mps) {
  Simulation sim(robot, WorldDescription{});
  ControlInput in;
  in.fresh = true;
  in.failsafe = false;
  in.deadman = true;
  const auto& m = robot.control;
  if (m.enable) in.switch_labels[m.enable->first] = m.enable->second;
  double scale = 1.0;
  if (m.speed_scale) {
    const auto& values = m.speed_scale->second;
    const auto best = std::max_element(values.begin(), values.end()) - values.begin();
    in.switches[m.speed_scale->first] = static_cast<int>(best);
    scale = values[static_cast<std::size_t>(best)];
  }
  if (m.estop_button) in.buttons[*m.estop_button] = false;
  if (robot.kind == RobotKind::UrdfTree) {
    // Its velocity joints (wheels) at full command: the fastest it goes.
    for (const auto& j : m.joints)
      if (j.mode == JointControlMode::Velocity && !j.axis.axis.empty()) in.axes[j.axis.axis] = j.axis.invert ? -1.0f : 1.0f;
  } else {
    const double full = scale * m.linear.max;
    const double value = std::clamp(speed_mps / full, 0.0, 1.0);
    in.axes[m.linear.axis] = static_cast<float>(m.linear.invert ? -value : value);
  }
  sim.set_input(in);
  // Spin up until the speed settles (or 10 s), then take motion away.
  double last = -1.0;
  for (int i = 0; i < 10000; ++i) {
    sim.step();
    if (i % 100 == 99) {
      const double v = sim.snapshot().speed_mps();
      if (std::fabs(v - last) < 1e-3) break;
      last = v;
    }
  }
  in.deadman = false;
  sim.set_input(in);
  const double start = sim.time_s();
  for (int i = 0; i < 10000; ++i) {
    sim.step();
    const auto s = sim.snapshot();
    if (s.speed_mps() < 0.01 && std::fabs(s.angular_velocity_radps[2]) < 0.02) return sim.time_s() - start;
  }
  return sim.time_s() - start;
}

}  // namespace rise::sim
