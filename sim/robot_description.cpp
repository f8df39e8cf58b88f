#include "sim/robot_description.hpp"

#include <cmath>
#include <filesystem>
#include <tuple>

#include "sim/urdf_robot.hpp"
#include "panels/yaml_reader.hpp"

namespace rise::sim {

using panels::YamlReader;

namespace {

constexpr double kDeg = M_PI / 180.0;

AxisMapping parse_axis(const YamlReader& r, const YAML::Node& n, const std::string& where) {
  r.only_keys(n, where, {"axis", "max_mps", "max_radps", "invert"});
  AxisMapping m;
  if (!n["axis"]) r.fail(n, where + ".axis", "missing");
  m.axis = r.as<std::string>(n["axis"], where + ".axis");
  const char* max_key = n["max_mps"] ? "max_mps" : "max_radps";
  if (!n[max_key]) r.fail(n, where + ".max_mps", "missing (max_mps or max_radps)");
  m.max = r.positive(n, max_key, where, 0.0);
  if (n["invert"]) m.invert = r.as<bool>(n["invert"], where + ".invert");
  return m;
}

std::pair<std::string, std::string> parse_enable(const YamlReader& r, const YAML::Node& e, const std::string& where) {
  r.only_keys(e, where, {"switch", "position"});
  if (!e["switch"] || !e["position"]) r.fail(e, where, "needs switch and position");
  return std::make_pair(r.as<std::string>(e["switch"], where + ".switch"),
                        r.as<std::string>(e["position"], where + ".position"));
}

ArmJointMapping parse_arm_joint(const YamlReader& r, const YAML::Node& n, const std::string& joint,
                                const std::string& where, bool limits_here) {
  r.only_keys(n, where, {"axis", "max_radps", "invert", "min_deg", "max_deg", "max_torque_nm", "break_torque_nm"});
  ArmJointMapping j;
  j.joint = joint;
  if (!n["axis"]) r.fail(n, where + ".axis", "missing");
  j.axis.axis = r.as<std::string>(n["axis"], where + ".axis");
  if (!n["max_radps"]) r.fail(n, where + ".max_radps", "missing");
  j.axis.max = r.positive(n, "max_radps", where, 0.0);
  if (n["invert"]) j.axis.invert = r.as<bool>(n["invert"], where + ".invert");
  for (const char* key : {"min_deg", "max_deg"})
    if (!limits_here && n[key]) r.fail(n[key], where + "." + key, "comes from the URDF joint's limit");
  if (n["min_deg"]) j.min_rad = r.as<double>(n["min_deg"], where + ".min_deg") * kDeg;
  if (n["max_deg"]) j.max_rad = r.as<double>(n["max_deg"], where + ".max_deg") * kDeg;
  if (limits_here && !(j.min_rad < 0.0 && j.max_rad > 0.0))
    r.fail(n, where + ".min_deg", "limits must include 0 (min < 0 < max)");
  j.max_torque_nm = r.positive(n, "max_torque_nm", where, j.max_torque_nm);
  j.break_torque_nm = r.positive(n, "break_torque_nm", where, j.break_torque_nm);
  return j;
}

Mount parse_mount(const YamlReader& r, const YAML::Node& n, const std::string& where) {
  Mount m;
  m.position_m = r.vector<3>(n, "mount_m", where);
  if (n["rpy_deg"]) {
    m.rpy_rad = r.vector<3>(n, "rpy_deg", where);
    for (double& a : m.rpy_rad) a *= kDeg;
  }
  return m;
}

LaserDescription parse_laser(const YamlReader& r, const YAML::Node& n, const std::string& where) {
  r.only_keys(n, where, {"mount_m", "rpy_deg", "fov_deg", "resolution_deg", "range_m", "noise_m", "rotating"});
  LaserDescription l;
  l.mount = parse_mount(r, n, where);
  l.fov_rad = r.positive(n, "fov_deg", where, l.fov_rad / kDeg) * kDeg;
  if (l.fov_rad > 2 * M_PI + 1e-9) r.fail(n["fov_deg"], where + ".fov_deg", "must be <= 360");
  l.resolution_rad = r.positive(n, "resolution_deg", where, l.resolution_rad / kDeg) * kDeg;
  if (l.resolution_rad > l.fov_rad) r.fail(n["resolution_deg"], where + ".resolution_deg", "must be <= fov_deg");
  if (n["range_m"]) {
    const auto range = r.vector<2>(n, "range_m", where);
    if (!(range[0] >= 0.0 && range[1] > range[0]))
      r.fail(n["range_m"], where + ".range_m", "expected [min, max] with 0 <= min < max");
    l.min_range_m = range[0];
    l.max_range_m = range[1];
  }
  l.noise_m = r.positive(n, "noise_m", where, l.noise_m, true);
  if (const YAML::Node rot = n["rotating"]) {
    const std::string w = where + ".rotating";
    r.only_keys(rot, w, {"axis", "steps", "sweep_deg"});
    LaserRotation t;
    if (rot["axis"]) {
      const auto axis = r.as<std::string>(rot["axis"], w + ".axis");
      if (axis != "x" && axis != "y" && axis != "z") r.fail(rot["axis"], w + ".axis", "expected x, y or z");
      t.axis = axis[0] - 'x';
    }
    if (!rot["steps"]) r.fail(rot, w + ".steps", "missing");
    t.steps = r.as<int>(rot["steps"], w + ".steps");
    if (t.steps < 1 || t.steps > 10000) r.fail(rot["steps"], w + ".steps", "must be in 1..10000");
    t.sweep_rad = r.positive(rot, "sweep_deg", w, t.sweep_rad / kDeg) * kDeg;
    if (t.sweep_rad > 2 * M_PI + 1e-9) r.fail(rot["sweep_deg"], w + ".sweep_deg", "must be <= 360");
    l.rotating = t;
  }
  if (static_cast<double>(l.beams()) * l.lines() > 1e7) r.fail(n, where, "more than 10 million rays per scan");
  return l;
}

SensorsDescription parse_sensors(const YamlReader& r, const YAML::Node& n) {
  r.only_keys(n, "sensors", {"seed", "laser", "odometry", "imu", "cameras"});
  SensorsDescription s;
  if (n["seed"]) s.seed = r.as<uint64_t>(n["seed"], "sensors.seed");
  if (const YAML::Node l = n["laser"]) s.laser = parse_laser(r, l, "sensors.laser");
  if (const YAML::Node o = n["odometry"]) {
    r.only_keys(o, "sensors.odometry", {"scale_sigma", "noise_per_sqrt_m"});
    s.odometry.scale_sigma = r.positive(o, "scale_sigma", "sensors.odometry", 0.0, true);
    s.odometry.noise_per_sqrt_m = r.positive(o, "noise_per_sqrt_m", "sensors.odometry", 0.0, true);
  }
  if (const YAML::Node i = n["imu"]) {
    const std::string w = "sensors.imu";
    r.only_keys(i, w, {"gyro_noise_radps", "gyro_bias_radps", "accel_noise_mps2", "accel_bias_mps2"});
    s.imu.gyro_noise_radps = r.positive(i, "gyro_noise_radps", w, 0.0, true);
    s.imu.gyro_bias_radps = r.positive(i, "gyro_bias_radps", w, 0.0, true);
    s.imu.accel_noise_mps2 = r.positive(i, "accel_noise_mps2", w, 0.0, true);
    s.imu.accel_bias_mps2 = r.positive(i, "accel_bias_mps2", w, 0.0, true);
  }
  if (const YAML::Node cams = n["cameras"]) {
    if (!cams.IsSequence()) r.fail(cams, "sensors.cameras", "expected a list");
    for (std::size_t k = 0; k < cams.size(); ++k) {
      const std::string w = "sensors.cameras[" + std::to_string(k) + "]";
      r.only_keys(cams[k], w, {"name", "mount_m", "rpy_deg"});
      if (!cams[k]["name"]) r.fail(cams[k], w + ".name", "missing");
      CameraMount c{r.as<std::string>(cams[k]["name"], w + ".name"), parse_mount(r, cams[k], w)};
      for (const auto& other : s.cameras)
        if (other.name == c.name) r.fail(cams[k]["name"], w + ".name", "duplicate camera '" + c.name + "'");
      s.cameras.push_back(c);
    }
  }
  return s;
}

/// The URDF joint names listed at map[key].joints (four names).
// sounds: {name: {source: ..., ...} | {on: ..., ...}, ...}, in file order.
std::vector<SoundCueDescription> parse_sounds(const YamlReader& r, const YAML::Node& n, bool has_arm) {
  if (!n.IsMap()) r.fail(n, "sounds", "expected a mapping of cue names to cues");
  std::vector<SoundCueDescription> cues;
  for (const auto& kv : n) {
    SoundCueDescription c;
    c.name = r.as<std::string>(kv.first, "sounds");
    const std::string where = "sounds." + c.name;
    const YAML::Node q = kv.second;
    if (!q.IsMap()) r.fail(q, where, "expected a mapping with source (continuous) or on (one-shot)");
    if (q["source"] && q["on"]) r.fail(q, where, "source (continuous) or on (one-shot), not both");
    if (!q["source"] && !q["on"]) r.fail(q, where, "needs source (continuous) or on (one-shot)");
    c.sample = q["sample"] ? r.as<std::string>(q["sample"], where + ".sample") : c.name;
    if (c.sample.empty()) r.fail(q["sample"], where + ".sample", "must not be empty");
    const auto unit_range = [&](const char* key, std::array<double, 2>& out, double hi) {
      const YAML::Node v = q[key];
      if (!v) return;
      if (!v.IsSequence() || v.size() != 2) r.fail(v, where + "." + key, "expected [at rest, at full_at]");
      for (std::size_t i = 0; i < 2; ++i) {
        out[i] = r.as<double>(v[i], where + "." + key);
        if (!(out[i] >= 0.0 && out[i] <= hi)) r.fail(v[i], where + "." + key, hi == 1.0 ? "must be in 0..1" : "must be in 0..4");
      }
    };
    if (const YAML::Node src = q["source"]) {
      r.only_keys(q, where, {"source", "full_at", "silent_below", "gain", "pitch", "sample"});
      const auto name = r.as<std::string>(src, where + ".source");
      if (name == "drive_speed") c.source = SoundSource::DriveSpeed;
      else if (name == "arm_rate") c.source = SoundSource::ArmRate;
      else if (name == "gripper_speed") c.source = SoundSource::GripperSpeed;
      else r.fail(src, where + ".source", "expected drive_speed, arm_rate or gripper_speed");
      if (c.source != SoundSource::DriveSpeed && !has_arm) r.fail(src, where + ".source", "the robot has no arm");
      c.full_at = r.positive(q, "full_at", where, c.full_at);
      c.silent_below = r.positive(q, "silent_below", where, c.silent_below, true);
      if (c.silent_below >= c.full_at) r.fail(q["silent_below"], where + ".silent_below", "must be below full_at");
      unit_range("gain", c.gain_range, 1.0);
      unit_range("pitch", c.pitch_range, 4.0);
      if (c.pitch_range[0] <= 0.0 || c.pitch_range[1] <= 0.0) r.fail(q["pitch"], where + ".pitch", "must be > 0");
    } else {
      r.only_keys(q, where, {"on", "button", "gain", "pitch", "gain_per_mps", "min_impact_mps", "sample"});
      const YAML::Node on = q["on"];
      const auto name = r.as<std::string>(on, where + ".on");
      static const std::pair<const char*, SoundTrigger> kTriggers[] = {
          {"collision_started", SoundTrigger::CollisionStarted}, {"joint_broken", SoundTrigger::JointBroken},
          {"door_opened", SoundTrigger::DoorOpened},             {"door_closed", SoundTrigger::DoorClosed},
          {"tipped_over", SoundTrigger::TippedOver},             {"stairs_climbed", SoundTrigger::StairsClimbed},
          {"region_entered", SoundTrigger::RegionEntered},       {"button", SoundTrigger::Button}};
      for (const auto& [key, trigger] : kTriggers)
        if (name == key) c.trigger = trigger;
      if (!c.trigger)
        r.fail(on, where + ".on",
               "expected collision_started, joint_broken, door_opened, door_closed, tipped_over, stairs_climbed, "
               "region_entered or button");
      if ((c.trigger == SoundTrigger::Button) != static_cast<bool>(q["button"]))
        r.fail(q["button"] ? q["button"] : q, where + ".button",
               c.trigger == SoundTrigger::Button ? "missing: which panel button" : "only with on: button");
      if (q["button"]) c.button = r.as<std::string>(q["button"], where + ".button");
      c.gain = r.positive(q, "gain", where, c.gain, true);
      if (c.gain > 1.0) r.fail(q["gain"], where + ".gain", "must be in 0..1");
      c.pitch = r.positive(q, "pitch", where, c.pitch);
      if (c.pitch > 4.0) r.fail(q["pitch"], where + ".pitch", "must be in 0..4");
      for (const char* key : {"gain_per_mps", "min_impact_mps"})
        if (q[key] && c.trigger != SoundTrigger::CollisionStarted)
          r.fail(q[key], where + "." + key, "only with on: collision_started");
      c.gain_per_mps = r.positive(q, "gain_per_mps", where, c.gain_per_mps, true);
      c.min_impact_mps = r.positive(q, "min_impact_mps", where, c.min_impact_mps, true);
    }
    cues.push_back(c);
  }
  return cues;
}

std::array<std::string, 4> joint_names(const YamlReader& r, const YAML::Node& map, const std::string& key) {
  const YAML::Node j = map["joints"];
  const std::string k = key + ".joints";
  if (!j || !j.IsSequence() || j.size() != 4) r.fail(j ? j : map, k, "expected a list of 4 URDF joint names");
  std::array<std::string, 4> names;
  for (std::size_t i = 0; i < 4; ++i) names[i] = r.as<std::string>(j[i], k);
  return names;
}

/// Fills the chassis, wheel and arm geometry from the URDF that root["urdf"]
/// names (relative to the robot file); returns the arm's joint limits.
std::vector<std::pair<double, double>> apply_urdf(const YamlReader& r, const YAML::Node& root, RobotDescription& d) {
  const YAML::Node urdf = root["urdf"];
  const auto name = r.as<std::string>(urdf, "urdf");
  if (const YAML::Node c = root["chassis"]) {
    if (d.kind == RobotKind::SkidSteer)
      r.fail(c, "chassis", "comes from the URDF (clearance from the wheel joints' height)");
    r.only_keys(c, "chassis", {"clearance_m"});
    d.chassis.clearance_m = r.positive(c, "clearance_m", "chassis", d.chassis.clearance_m, true);
  }
  UrdfJointNames joints;
  if (d.kind == RobotKind::SkidSteer) {
    const YAML::Node w = root["wheels"];
    if (!w.IsMap() || !w["joints"]) r.fail(w, "wheels.joints", "missing: the URDF joints of the wheels (fl, fr, rl, rr)");
    joints.wheels = joint_names(r, w, "wheels");
  }
  if (const YAML::Node a = root["arm"]) {
    r.only_keys(a, "arm", {"joints"});
    joints.arm = joint_names(r, a, "arm");
  }
  const std::filesystem::path path = std::filesystem::path(r.file()).parent_path() / name;
  UrdfRobot u;
  try {
    u = read_urdf_robot(path.string(), joints);
  } catch (const std::runtime_error& e) {
    r.fail(urdf, "urdf", name + ": " + e.what());
  }
  d.chassis.size_m = u.chassis_size_m;
  d.chassis.mass_kg = u.chassis_mass_kg;
  if (u.clearance_m) d.chassis.clearance_m = *u.clearance_m;
  if (u.wheels) {
    d.wheels.radius_m = u.wheels->radius_m;
    d.wheels.width_m = u.wheels->width_m;
    d.wheels.mass_kg = u.wheels->mass_kg;
    d.wheels.wheelbase_m = u.wheels->wheelbase_m;
    d.wheels.track_m = u.wheels->track_m;
  }
  d.arm = u.arm;
  if (!u.arm) return {};
  return {u.arm_limits_rad.begin(), u.arm_limits_rad.end()};
}

// The chassis of a robot file without a URDF.
void parse_chassis(const YamlReader& r, const YAML::Node& root, ChassisDescription& c) {
  const YAML::Node chassis = root["chassis"];
  if (!chassis) r.fail(root, "chassis", "missing");
  r.only_keys(chassis, "chassis", {"size_m", "mass_kg", "clearance_m"});
  if (const YAML::Node size = chassis["size_m"]) {
    if (!size.IsSequence() || size.size() != 3) r.fail(size, "chassis.size_m", "expected [length, width, height]");
    for (std::size_t i = 0; i < 3; ++i) {
      c.size_m[i] = r.as<double>(size[i], "chassis.size_m");
      if (!(c.size_m[i] > 0)) r.fail(size[i], "chassis.size_m", "must be > 0");
    }
  }
  c.mass_kg = r.positive(chassis, "mass_kg", "chassis", c.mass_kg);
  c.clearance_m = r.positive(chassis, "clearance_m", "chassis", c.clearance_m, true);
}

// A skid-steer's wheels (their geometry from the URDF when there is one).
void parse_wheels(const YamlReader& r, const YAML::Node& wheels, bool urdf, RobotDescription& d) {
  auto& w = d.wheels;
  if (urdf) {
    r.only_keys(wheels, "wheels", {"joints", "friction", "max_torque_nm", "max_speed_radps"});
  } else {
    r.only_keys(wheels, "wheels", {"radius_m", "width_m", "mass_kg", "friction", "wheelbase_m", "track_m",
                                   "max_torque_nm", "max_speed_radps"});
    w.radius_m = r.positive(wheels, "radius_m", "wheels", w.radius_m);
    w.width_m = r.positive(wheels, "width_m", "wheels", w.width_m);
    w.mass_kg = r.positive(wheels, "mass_kg", "wheels", w.mass_kg);
    w.wheelbase_m = r.positive(wheels, "wheelbase_m", "wheels", w.wheelbase_m);
    w.track_m = r.positive(wheels, "track_m", "wheels", w.track_m);
    if (w.track_m <= w.width_m) r.fail(wheels["track_m"], "wheels.track_m", "must be wider than a wheel");
    if (w.radius_m <= d.chassis.clearance_m)
      r.fail(wheels["radius_m"], "wheels.radius_m", "must exceed chassis.clearance_m");
  }
  w.friction = r.positive(wheels, "friction", "wheels", w.friction);
  w.max_torque_nm = r.positive(wheels, "max_torque_nm", "wheels", w.max_torque_nm);
  w.max_speed_radps = r.positive(wheels, "max_speed_radps", "wheels", w.max_speed_radps);
}

void parse_tracks(const YamlReader& r, const YAML::Node& root, RobotDescription& d) {
  const YAML::Node tracks = root["tracks"];
  if (!tracks) r.fail(root, "tracks", "missing");
  r.only_keys(tracks, "tracks", {"length_m", "radius_m", "gauge_m", "approach_deg", "approach_length_m", "friction",
                                 "lateral_friction", "max_speed_mps"});
  auto& t = d.tracks;
  t.length_m = r.positive(tracks, "length_m", "tracks", t.length_m);
  t.radius_m = r.positive(tracks, "radius_m", "tracks", t.radius_m);
  t.gauge_m = r.positive(tracks, "gauge_m", "tracks", t.gauge_m);
  t.approach_rad = r.positive(tracks, "approach_deg", "tracks", t.approach_rad * 180.0 / M_PI, true) * M_PI / 180.0;
  if (t.approach_rad > M_PI / 2) r.fail(tracks["approach_deg"], "tracks.approach_deg", "must be <= 90");
  t.approach_length_m = r.positive(tracks, "approach_length_m", "tracks", t.approach_length_m, true);
  t.friction = r.positive(tracks, "friction", "tracks", t.friction);
  t.lateral_friction = r.positive(tracks, "lateral_friction", "tracks", t.lateral_friction);
  t.max_speed_mps = r.positive(tracks, "max_speed_mps", "tracks", t.max_speed_mps);
  if (t.radius_m * 2 <= d.chassis.clearance_m)
    r.fail(tracks["radius_m"], "tracks.radius_m", "the tracks must reach above chassis.clearance_m");
}

// The arm of a robot file without a URDF.
ArmDescription parse_arm(const YamlReader& r, const YAML::Node& arm) {
  r.only_keys(arm, "arm", {"mount_m", "upper_length_m", "forearm_length_m", "link_mass_kg", "link_width_m",
                           "gripper_stroke_m"});
  ArmDescription a;
  if (const YAML::Node m = arm["mount_m"]) {
    if (!m.IsSequence() || m.size() != 2) r.fail(m, "arm.mount_m", "expected [x, y]");
    for (std::size_t i = 0; i < 2; ++i) a.mount_m[i] = r.as<double>(m[i], "arm.mount_m");
  }
  a.upper_length_m = r.positive(arm, "upper_length_m", "arm", a.upper_length_m);
  a.forearm_length_m = r.positive(arm, "forearm_length_m", "arm", a.forearm_length_m);
  a.link_mass_kg = r.positive(arm, "link_mass_kg", "arm", a.link_mass_kg);
  a.link_width_m = r.positive(arm, "link_width_m", "arm", a.link_width_m);
  a.gripper_stroke_m = r.positive(arm, "gripper_stroke_m", "arm", a.gripper_stroke_m);
  return a;
}

std::pair<std::string, std::vector<double>> parse_speed_scale(const YamlReader& r, const YAML::Node& s) {
  r.only_keys(s, "control.speed_scale", {"switch", "values"});
  const YAML::Node values = s["values"];
  if (!s["switch"] || !values || !values.IsSequence() || values.size() == 0)
    r.fail(s, "control.speed_scale", "needs switch and a list of values");
  std::vector<double> scale;
  for (const auto& v : values) {
    const double x = r.as<double>(v, "control.speed_scale.values");
    if (!(x >= 0.0 && x <= 1.0)) r.fail(v, "control.speed_scale.values", "must be in 0..1");
    scale.push_back(x);
  }
  return std::make_pair(r.as<std::string>(s["switch"], "control.speed_scale.switch"), scale);
}

// control.arm; the joints' limits from the URDF when it gave them
// (urdf_arm_limits, in joint order), else from here.
ArmMapping parse_arm_mapping(const YamlReader& r, const YAML::Node& arm_control,
                             const std::vector<std::pair<double, double>>& urdf_arm_limits) {
  r.only_keys(arm_control, "control.arm", {"enable", "shoulder_yaw", "shoulder_pitch", "elbow_pitch", "gripper"});
  ArmMapping a;
  if (const YAML::Node e = arm_control["enable"]) a.enable = parse_enable(r, e, "control.arm.enable");
  for (const char* joint : {"shoulder_yaw", "shoulder_pitch", "elbow_pitch"}) {
    const std::string where = std::string("control.arm.") + joint;
    if (!arm_control[joint]) r.fail(arm_control, where, "missing");
    a.joints.push_back(parse_arm_joint(r, arm_control[joint], joint, where, urdf_arm_limits.empty()));
    if (!urdf_arm_limits.empty()) std::tie(a.joints.back().min_rad, a.joints.back().max_rad) = urdf_arm_limits[a.joints.size() - 1];
  }
  const YAML::Node g = arm_control["gripper"];
  if (!g) r.fail(arm_control, "control.arm.gripper", "missing");
  r.only_keys(g, "control.arm.gripper", {"open", "close", "speed_mps", "max_force_n"});
  if (!g["open"] || !g["close"]) r.fail(g, "control.arm.gripper", "needs open and close buttons");
  a.open_button = r.as<std::string>(g["open"], "control.arm.gripper.open");
  a.close_button = r.as<std::string>(g["close"], "control.arm.gripper.close");
  a.gripper_speed_mps = r.positive(g, "speed_mps", "control.arm.gripper", a.gripper_speed_mps);
  a.gripper_max_force_n = r.positive(g, "max_force_n", "control.arm.gripper", a.gripper_max_force_n);
  return a;
}

// Which panel controls drive the robot and move its arm.
void parse_control(const YamlReader& r, const YAML::Node& root,
                   const std::vector<std::pair<double, double>>& urdf_arm_limits, RobotDescription& d) {
  const YAML::Node control = root["control"];
  if (!control) r.fail(root, "control", "missing: which panel controls drive the robot");
  r.only_keys(control, "control", {"linear", "angular", "enable", "speed_scale", "estop", "arm"});
  if (!control["linear"]) r.fail(control, "control.linear", "missing");
  if (!control["angular"]) r.fail(control, "control.angular", "missing");
  d.control.linear = parse_axis(r, control["linear"], "control.linear");
  d.control.angular = parse_axis(r, control["angular"], "control.angular");
  if (const YAML::Node e = control["enable"]) d.control.enable = parse_enable(r, e, "control.enable");
  if (const YAML::Node s = control["speed_scale"]) d.control.speed_scale = parse_speed_scale(r, s);
  if (const YAML::Node e = control["estop"]) {
    r.only_keys(e, "control.estop", {"button"});
    if (!e["button"]) r.fail(e, "control.estop.button", "missing");
    d.control.estop_button = r.as<std::string>(e["button"], "control.estop.button");
  }
  const YAML::Node arm_control = control["arm"];
  if (d.arm && !arm_control) r.fail(control, "control.arm", "missing: which panel controls move the arm");
  if (!d.arm && arm_control) r.fail(arm_control, "control.arm", "the robot has no arm section");
  if (arm_control) d.control.arm = parse_arm_mapping(r, arm_control, urdf_arm_limits);
}

// control.joints.<name>: one panel-driven joint of a urdf_tree robot.
JointControl parse_joint_control(const YamlReader& r, const YAML::Node& n, const std::string& name,
                                 const UrdfTree& tree) {
  const std::string where = "control.joints." + name;
  r.only_keys(n, where, {"mode", "axis", "max", "invert", "mix", "buttons", "enable", "max_effort", "gain_per_s"});
  JointControl c;
  c.joint = name;
  const std::size_t j = tree.joint_index(name);
  if (j == tree.joints.size()) r.fail(n, where, "no joint '" + name + "' in the URDF");
  const UrdfJoint& joint = tree.joints[j];
  if (joint.type == UrdfJointType::Fixed) r.fail(n, where, "joint '" + name + "' is fixed");
  if (n["mode"]) {
    const auto mode = r.as<std::string>(n["mode"], where + ".mode");
    if (mode == "position") c.mode = JointControlMode::Position;
    else if (mode == "velocity") c.mode = JointControlMode::Velocity;
    else if (mode == "effort") c.mode = JointControlMode::Effort;
    else r.fail(n["mode"], where + ".mode", "expected position, velocity or effort");
  }
  if (c.mode == JointControlMode::Position && joint.type == UrdfJointType::Continuous)
    r.fail(n["mode"], where + ".mode", "a continuous joint has no position limits: use velocity or effort");
  if (!n["axis"] && !n["buttons"]) r.fail(n, where + ".axis", "missing (axis or buttons)");
  if (n["axis"]) c.axis.axis = r.as<std::string>(n["axis"], where + ".axis");
  if (!n["max"]) r.fail(n, where + ".max", "missing: the command at full deflection");
  c.axis.max = r.positive(n, "max", where, 0.0);
  if (n["invert"]) c.axis.invert = r.as<bool>(n["invert"], where + ".invert");
  if (const YAML::Node m = n["mix"]) {
    r.only_keys(m, where + ".mix", {"axis", "max", "invert"});
    if (!m["axis"] || !m["max"]) r.fail(m, where + ".mix", "needs axis and max");
    AxisMapping mix;
    mix.axis = r.as<std::string>(m["axis"], where + ".mix.axis");
    mix.max = r.positive(m, "max", where + ".mix", 0.0);
    if (m["invert"]) mix.invert = r.as<bool>(m["invert"], where + ".mix.invert");
    c.mix = mix;
  }
  if (const YAML::Node b = n["buttons"]) {
    if (!b.IsSequence() || b.size() != 2) r.fail(b, where + ".buttons", "expected [plus, minus]");
    c.buttons = std::make_pair(r.as<std::string>(b[0], where + ".buttons"), r.as<std::string>(b[1], where + ".buttons"));
  }
  if (const YAML::Node e = n["enable"]) c.enable = parse_enable(r, e, where + ".enable");
  c.max_effort = r.positive(n, "max_effort", where, joint.effort > 0 ? joint.effort : 0.0, true);
  if (!(c.max_effort > 0))
    r.fail(n, where + ".max_effort", "missing: the URDF joint's limit gives no effort");
  c.gain_per_s = r.positive(n, "gain_per_s", where, c.gain_per_s);
  return c;
}

// A urdf_tree robot: the URDF's tree, its links' friction and the joints the panel drives.
void parse_tree_robot(const YamlReader& r, const YAML::Node& root, RobotDescription& d) {
  for (const char* key : {"chassis", "wheels", "tracks", "arm"})
    if (root[key]) r.fail(root[key], key, "a urdf_tree robot takes its body from the URDF");
  const YAML::Node urdf = root["urdf"];
  if (!urdf) r.fail(root, "urdf", "missing: a urdf_tree robot's links and joints");
  const auto name = r.as<std::string>(urdf, "urdf");
  const std::filesystem::path path = std::filesystem::path(r.file()).parent_path() / name;
  try {
    d.tree = read_urdf_tree(path.string());
  } catch (const std::runtime_error& e) {
    r.fail(urdf, "urdf", name + ": " + e.what());
  }
  if (const YAML::Node links = root["links"]) {
    if (!links.IsMap()) r.fail(links, "links", "expected a mapping of link names to {friction}");
    for (const auto& kv : links) {
      const auto link = r.as<std::string>(kv.first, "links");
      const std::string where = "links." + link;
      if (d.tree->link_index(link) == d.tree->links.size()) r.fail(kv.first, where, "no link '" + link + "' in the URDF");
      r.only_keys(kv.second, where, {"friction"});
      d.link_friction.emplace_back(link, r.positive(kv.second, "friction", where, 1.0, true));
    }
  }
  const YAML::Node control = root["control"];
  if (!control) r.fail(root, "control", "missing: which panel controls drive the robot's joints");
  r.only_keys(control, "control", {"enable", "speed_scale", "estop", "joints"});
  if (const YAML::Node e = control["enable"]) d.control.enable = parse_enable(r, e, "control.enable");
  if (const YAML::Node s = control["speed_scale"]) d.control.speed_scale = parse_speed_scale(r, s);
  if (const YAML::Node e = control["estop"]) {
    r.only_keys(e, "control.estop", {"button"});
    if (!e["button"]) r.fail(e, "control.estop.button", "missing");
    d.control.estop_button = r.as<std::string>(e["button"], "control.estop.button");
  }
  const YAML::Node joints = control["joints"];
  if (!joints || !joints.IsMap() || joints.size() == 0)
    r.fail(joints ? joints : control, "control.joints", "missing: a mapping of URDF joint names to controls");
  for (const auto& kv : joints) {
    const auto joint = r.as<std::string>(kv.first, "control.joints");
    for (const auto& other : d.control.joints)
      if (other.joint == joint) r.fail(kv.first, "control.joints." + joint, "joint mapped twice");
    d.control.joints.push_back(parse_joint_control(r, kv.second, joint, *d.tree));
  }
}

}  // namespace

RobotDescription parse_robot_description(const std::string& text, const std::string& file) {
  const YamlReader r(file);
  const YAML::Node root = r.load_text(text);
  if (!root.IsMap()) r.fail(root, "", "expected a mapping with robot, chassis, wheels, control");
  r.only_keys(root, "", {"robot", "kind", "urdf", "chassis", "wheels", "tracks", "arm", "links", "control", "sensors",
                         "sounds"});
  RobotDescription d;
  d.file = file;
  if (!root["robot"]) r.fail(root, "robot", "missing");
  d.name = r.as<std::string>(root["robot"], "robot");
  if (const YAML::Node k = root["kind"]) {
    const auto kind = r.as<std::string>(k, "kind");
    if (kind == "skid_steer") d.kind = RobotKind::SkidSteer;
    else if (kind == "tracked") d.kind = RobotKind::Tracked;
    else if (kind == "urdf_tree") d.kind = RobotKind::UrdfTree;
    else r.fail(k, "kind", "expected skid_steer, tracked or urdf_tree");
  }
  if (d.kind == RobotKind::UrdfTree) {
    parse_tree_robot(r, root, d);
    if (const YAML::Node sensors = root["sensors"]) d.sensors = parse_sensors(r, sensors);
    if (const YAML::Node sounds = root["sounds"]) d.sounds = parse_sounds(r, sounds, true);
    return d;
  }
  if (const YAML::Node links = root["links"]) r.fail(links, "links", "only for kind: urdf_tree");

  const YAML::Node urdf = root["urdf"];
  std::vector<std::pair<double, double>> urdf_arm_limits;
  const YAML::Node wheels = root["wheels"];
  if (d.kind == RobotKind::Tracked && wheels) r.fail(wheels, "wheels", "a tracked robot has tracks, not wheels");
  if (d.kind == RobotKind::SkidSteer && root["tracks"])
    r.fail(root["tracks"], "tracks", "a skid_steer robot has wheels");
  if (d.kind == RobotKind::SkidSteer && !wheels) r.fail(root, "wheels", "missing");
  if (urdf) urdf_arm_limits = apply_urdf(r, root, d);
  else parse_chassis(r, root, d.chassis);

  if (d.kind == RobotKind::SkidSteer) parse_wheels(r, wheels, static_cast<bool>(urdf), d);
  else parse_tracks(r, root, d);
  if (const YAML::Node arm = root["arm"]; arm && !urdf) d.arm = parse_arm(r, arm);
  parse_control(r, root, urdf_arm_limits, d);
  if (const YAML::Node sensors = root["sensors"]) d.sensors = parse_sensors(r, sensors);
  if (const YAML::Node sounds = root["sounds"]) d.sounds = parse_sounds(r, sounds, d.arm.has_value());
  return d;
}

const char* to_string(SoundSource source) {
  switch (source) {
    case SoundSource::DriveSpeed: return "drive_speed";
    case SoundSource::ArmRate: return "arm_rate";
    case SoundSource::GripperSpeed: return "gripper_speed";
  }
  return "unknown";
}

const char* to_string(SoundTrigger trigger) {
  switch (trigger) {
    case SoundTrigger::CollisionStarted: return "collision_started";
    case SoundTrigger::JointBroken: return "joint_broken";
    case SoundTrigger::DoorOpened: return "door_opened";
    case SoundTrigger::DoorClosed: return "door_closed";
    case SoundTrigger::TippedOver: return "tipped_over";
    case SoundTrigger::StairsClimbed: return "stairs_climbed";
    case SoundTrigger::RegionEntered: return "region_entered";
    case SoundTrigger::Button: return "button";
  }
  return "unknown";
}

RobotDescription load_robot_description(const std::string& path) {
  return parse_robot_description(panels::read_text_file(path), path);
}

}  // namespace rise::sim
