#include "sim/simulation.hpp"

#include <ode/ode.h>

#include <algorithm>
#include <atomic>
#include <cstdarg>
#include <cmath>
#include <mutex>
#include <set>

namespace rise::sim {
namespace {

// Contact springs for a 1 ms step: stiffness kp and damping kd turned into
// ODE's ERP/CFM (ODE manual, "Soft constraint and constraint force mixing").
constexpr double kContactKp = 2.0e5;  // N/m
constexpr double kContactKd = 2.0e3;  // N·s/m
constexpr double kLateralFrictionRatio = 0.6;  // tyre side grip vs rolling grip, lets skid steering turn
constexpr double kObstacleFriction = 0.5;
constexpr int kMaxContacts = 4;

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

enum class GeomKind { Ground, Obstacle, Chassis, Wheel };
struct GeomInfo {
  GeomKind kind;
  std::string name;
};

const char* kWheelNames[4] = {"wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"};

bool allowed(const ControlMapping& m, const ControlInput& in, std::string& reason) {
  if (!in.fresh) { reason = "no panel state"; return false; }
  if (in.failsafe) { reason = "panel failsafe"; return false; }
  if (m.estop_button) {
    const auto it = in.buttons.find(*m.estop_button);
    if (it == in.buttons.end() || it->second) { reason = "e-stop"; return false; }
  }
  if (!in.deadman) { reason = "dead-man released"; return false; }
  if (m.enable) {
    const auto it = in.switch_labels.find(m.enable->first);
    if (it == in.switch_labels.end() || it->second != m.enable->second) {
      reason = m.enable->first + " not " + m.enable->second;
      return false;
    }
  }
  return true;
}

double axis_value(const AxisMapping& a, const ControlInput& in) {
  const auto it = in.axes.find(a.axis);
  if (it == in.axes.end()) return 0.0;
  const double v = std::clamp(static_cast<double>(it->second), -1.0, 1.0);
  return (a.invert ? -v : v) * a.max;
}

}  // namespace

int64_t ode_messages() { return g_ode_messages.load(); }

double RobotSnapshot::yaw_rad() const {
  const auto& q = orientation_wxyz;
  return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
}

double RobotSnapshot::speed_mps() const { return std::hypot(linear_velocity_mps[0], linear_velocity_mps[1]); }

DriveCommand map_controls(const ControlMapping& mapping, const ControlInput& input) {
  DriveCommand c;
  if (!allowed(mapping, input, c.stop_reason)) return c;
  double scale = 1.0;
  if (mapping.speed_scale) {
    const auto it = input.switches.find(mapping.speed_scale->first);
    const auto& values = mapping.speed_scale->second;
    if (it == input.switches.end() || it->second < 0 || static_cast<std::size_t>(it->second) >= values.size()) {
      c.stop_reason = mapping.speed_scale->first + " position unknown";
      return c;
    }
    scale = values[static_cast<std::size_t>(it->second)];
  }
  c.linear_mps = scale * axis_value(mapping.linear, input);
  c.angular_radps = scale * axis_value(mapping.angular, input);
  c.enabled = true;
  return c;
}

struct Simulation::Impl {
  RobotDescription robot;
  WorldDescription world_desc;
  dWorldID world = nullptr;
  dSpaceID space = nullptr;
  dJointGroupID contacts = nullptr;
  dBodyID chassis = nullptr;
  std::array<dBodyID, 4> wheels{};
  std::array<dJointID, 4> hinges{};
  std::array<dJointFeedback, 4> feedback{};
  std::vector<std::unique_ptr<GeomInfo>> infos;
  std::set<std::string> touching;
  ControlInput input;
  DriveCommand command;
  int64_t steps = 0;

  dGeomID add_geom(dGeomID g, GeomKind kind, const std::string& name) {
    infos.push_back(std::make_unique<GeomInfo>(GeomInfo{kind, name}));
    dGeomSetData(g, infos.back().get());
    return g;
  }

  void build() {
    init_ode_once();
    world = dWorldCreate();
    dWorldSetGravity(world, 0, 0, -9.81);
    const double h = kStepS;
    dWorldSetERP(world, 0.2);
    dWorldSetCFM(world, 1e-5);
    dWorldSetContactSurfaceLayer(world, 0.0005);
    dWorldSetAutoDisableFlag(world, 0);
    (void)h;
    // A simple space keeps the collision order independent of memory
    // addresses: the same inputs give the same contacts, step for step.
    space = dSimpleSpaceCreate(nullptr);
    contacts = dJointGroupCreate(0);

    add_geom(dCreatePlane(space, 0, 0, 1, 0), GeomKind::Ground, "ground");
    for (const auto& b : world_desc.boxes) {
      dGeomID g = add_geom(dCreateBox(space, b.size_m[0], b.size_m[1], b.size_m[2]), GeomKind::Obstacle, b.name);
      dGeomSetPosition(g, b.center_m[0], b.center_m[1], b.center_m[2]);
      dMatrix3 R;
      dRFromAxisAndAngle(R, 0, 0, 1, b.yaw_rad);
      dGeomSetRotation(g, R);
    }

    const auto& c = robot.chassis;
    const auto& w = robot.wheels;
    const double chassis_z = c.clearance_m + c.size_m[2] / 2;
    chassis = dBodyCreate(world);
    dMass m;
    dMassSetBoxTotal(&m, c.mass_kg, c.size_m[0], c.size_m[1], c.size_m[2]);
    dBodySetMass(chassis, &m);
    dBodySetPosition(chassis, 0, 0, chassis_z);
    dGeomSetBody(add_geom(dCreateBox(space, c.size_m[0], c.size_m[1], c.size_m[2]), GeomKind::Chassis, "chassis"),
                 chassis);

    const double xs[4] = {w.wheelbase_m / 2, w.wheelbase_m / 2, -w.wheelbase_m / 2, -w.wheelbase_m / 2};
    const double ys[4] = {w.track_m / 2, -w.track_m / 2, w.track_m / 2, -w.track_m / 2};
    dMatrix3 R;
    dRFromAxisAndAngle(R, 1, 0, 0, M_PI / 2);  // cylinder axis (z) along the body's y
    for (std::size_t i = 0; i < 4; ++i) {
      wheels[i] = dBodyCreate(world);
      dMass wm;
      dMassSetCylinderTotal(&wm, w.mass_kg, 3, w.radius_m, w.width_m);
      dBodySetMass(wheels[i], &wm);
      dBodySetPosition(wheels[i], xs[i], ys[i], w.radius_m);
      dBodySetRotation(wheels[i], R);
      dGeomSetBody(add_geom(dCreateCylinder(space, w.radius_m, w.width_m), GeomKind::Wheel, kWheelNames[i]),
                   wheels[i]);
      hinges[i] = dJointCreateHinge(world, nullptr);
      dJointAttach(hinges[i], chassis, wheels[i]);
      dJointSetHingeAnchor(hinges[i], xs[i], ys[i], w.radius_m);
      // Axis along -y: a positive motor speed rolls the robot forward (+x).
      dJointSetHingeAxis(hinges[i], 0, -1, 0);
      dJointSetHingeParam(hinges[i], dParamFMax, w.max_torque_nm);
      dJointSetHingeParam(hinges[i], dParamVel, 0.0);
      dJointSetFeedback(hinges[i], &feedback[i]);
    }
  }

  static void near_callback(void* data, dGeomID a, dGeomID b) {
    static_cast<Impl*>(data)->collide(a, b);
  }

  void collide(dGeomID a, dGeomID b) {
    const dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
    if (ba && bb && dAreConnectedExcluding(ba, bb, dJointTypeContact)) return;
    const auto* ia = static_cast<const GeomInfo*>(dGeomGetData(a));
    const auto* ib = static_cast<const GeomInfo*>(dGeomGetData(b));
    const bool a_static = ia->kind == GeomKind::Ground || ia->kind == GeomKind::Obstacle;
    const bool b_static = ib->kind == GeomKind::Ground || ib->kind == GeomKind::Obstacle;
    if (a_static && b_static) return;

    dContact contact[kMaxContacts];
    const int n = dCollide(a, b, kMaxContacts, &contact[0].geom, sizeof(dContact));
    if (n <= 0) return;
    const GeomInfo* other = a_static ? ia : ib;
    const GeomInfo* mine = a_static ? ib : ia;
    if (other->kind == GeomKind::Obstacle) touching.insert(other->name);

    const double erp = kStepS * kContactKp / (kStepS * kContactKp + kContactKd);
    const double cfm = 1.0 / (kStepS * kContactKp + kContactKd);
    const bool wheel_on_ground = mine->kind == GeomKind::Wheel && other->kind == GeomKind::Ground;
    const double mu = wheel_on_ground ? std::min(robot.wheels.friction, world_desc.ground_friction)
                                      : kObstacleFriction;
    // Tyre friction is anisotropic: rolling direction along the chassis' x.
    const dReal* R = dBodyGetRotation(chassis);
    for (int i = 0; i < n; ++i) {
      dSurfaceParameters& s = contact[i].surface;
      s.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM;
      s.mu = mu;
      s.soft_erp = erp;
      s.soft_cfm = cfm;
      if (mine->kind == GeomKind::Wheel) {
        s.mode |= dContactMu2 | dContactFDir1;
        s.mu2 = mu * kLateralFrictionRatio;
        contact[i].fdir1[0] = R[0];
        contact[i].fdir1[1] = R[4];
        contact[i].fdir1[2] = R[8];
      }
      dJointID j = dJointCreateContact(world, contacts, &contact[i]);
      dJointAttach(j, dGeomGetBody(contact[i].geom.g1), dGeomGetBody(contact[i].geom.g2));
    }
  }

  void apply_command() {
    command = map_controls(robot.control, input);
    const auto& w = robot.wheels;
    double left = (command.linear_mps - command.angular_radps * w.track_m / 2) / w.radius_m;
    double right = (command.linear_mps + command.angular_radps * w.track_m / 2) / w.radius_m;
    // Saturate both sides together so the curvature the trainee asked for is kept.
    const double peak = std::max(std::fabs(left), std::fabs(right));
    if (peak > w.max_speed_radps) {
      left *= w.max_speed_radps / peak;
      right *= w.max_speed_radps / peak;
    }
    if (!command.enabled) left = right = 0.0;  // brake: the motors hold the wheels
    for (std::size_t i = 0; i < 4; ++i) dJointSetHingeParam(hinges[i], dParamVel, (i % 2 == 0) ? left : right);
  }

  void step() {
    apply_command();
    touching.clear();
    dSpaceCollide(space, this, &near_callback);
    dWorldStep(world, kStepS);
    dJointGroupEmpty(contacts);
    ++steps;
  }

  ~Impl() {
    if (contacts) dJointGroupDestroy(contacts);
    if (space) dSpaceDestroy(space);
    if (world) dWorldDestroy(world);
  }
};

Simulation::Simulation(RobotDescription robot, WorldDescription world) : impl_(std::make_unique<Impl>()) {
  impl_->robot = std::move(robot);
  impl_->world_desc = std::move(world);
  impl_->build();
}

Simulation::~Simulation() = default;

void Simulation::set_input(const ControlInput& input) { impl_->input = input; }
void Simulation::step() { impl_->step(); }
double Simulation::time_s() const { return static_cast<double>(impl_->steps) * kStepS; }
const RobotDescription& Simulation::robot() const { return impl_->robot; }

RobotSnapshot Simulation::snapshot() const {
  const Impl& s = *impl_;
  RobotSnapshot r;
  r.time_s = time_s();
  const dReal* p = dBodyGetPosition(s.chassis);
  const dReal* q = dBodyGetQuaternion(s.chassis);
  r.position_m = {p[0], p[1], p[2]};
  r.orientation_wxyz = {q[0], q[1], q[2], q[3]};
  dVector3 v, w;
  const dReal* lv = dBodyGetLinearVel(s.chassis);
  const dReal* av = dBodyGetAngularVel(s.chassis);
  dBodyVectorFromWorld(s.chassis, lv[0], lv[1], lv[2], v);
  dBodyVectorFromWorld(s.chassis, av[0], av[1], av[2], w);
  r.linear_velocity_mps = {v[0], v[1], v[2]};
  r.angular_velocity_radps = {w[0], w[1], w[2]};
  for (std::size_t i = 0; i < 4; ++i) {
    WheelState ws;
    ws.name = kWheelNames[i];
    ws.position_rad = dJointGetHingeAngle(s.hinges[i]);
    ws.velocity_radps = dJointGetHingeAngleRate(s.hinges[i]);
    dVector3 axis;
    dJointGetHingeAxis(s.hinges[i], axis);
    const auto& t = s.feedback[i].t2;  // torque on the wheel from the hinge
    ws.effort_nm = t[0] * axis[0] + t[1] * axis[1] + t[2] * axis[2];
    r.wheels.push_back(ws);
  }
  r.contacts.assign(s.touching.begin(), s.touching.end());
  r.motors_enabled = s.command.enabled;
  r.stop_reason = s.command.stop_reason;
  r.commanded_linear_mps = s.command.linear_mps;
  r.commanded_angular_radps = s.command.angular_radps;
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
  const double full = scale * m.linear.max;
  const double value = std::clamp(speed_mps / full, 0.0, 1.0);
  in.axes[m.linear.axis] = static_cast<float>(m.linear.invert ? -value : value);
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
