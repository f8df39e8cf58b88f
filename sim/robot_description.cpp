#include "sim/robot_description.hpp"

#include <fstream>
#include <sstream>

#include "sim/yaml_reader.hpp"

namespace rise::sim {
namespace {

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

}  // namespace

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ":0: cannot open");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

RobotDescription parse_robot_description(const std::string& text, const std::string& file) {
  const YamlReader r(file);
  const YAML::Node root = r.load_text(text);
  if (!root.IsMap()) r.fail(root, "", "expected a mapping with robot, chassis, wheels, control");
  r.only_keys(root, "", {"robot", "chassis", "wheels", "control"});
  RobotDescription d;
  d.file = file;
  if (!root["robot"]) r.fail(root, "robot", "missing");
  d.name = r.as<std::string>(root["robot"], "robot");

  const YAML::Node chassis = root["chassis"];
  if (!chassis) r.fail(root, "chassis", "missing");
  r.only_keys(chassis, "chassis", {"size_m", "mass_kg", "clearance_m"});
  if (const YAML::Node size = chassis["size_m"]) {
    if (!size.IsSequence() || size.size() != 3) r.fail(size, "chassis.size_m", "expected [length, width, height]");
    for (std::size_t i = 0; i < 3; ++i) {
      d.chassis.size_m[i] = r.as<double>(size[i], "chassis.size_m");
      if (!(d.chassis.size_m[i] > 0)) r.fail(size[i], "chassis.size_m", "must be > 0");
    }
  }
  d.chassis.mass_kg = r.positive(chassis, "mass_kg", "chassis", d.chassis.mass_kg);
  d.chassis.clearance_m = r.positive(chassis, "clearance_m", "chassis", d.chassis.clearance_m, true);

  const YAML::Node wheels = root["wheels"];
  if (!wheels) r.fail(root, "wheels", "missing");
  r.only_keys(wheels, "wheels", {"radius_m", "width_m", "mass_kg", "friction", "wheelbase_m", "track_m",
                                 "max_torque_nm", "max_speed_radps"});
  auto& w = d.wheels;
  w.radius_m = r.positive(wheels, "radius_m", "wheels", w.radius_m);
  w.width_m = r.positive(wheels, "width_m", "wheels", w.width_m);
  w.mass_kg = r.positive(wheels, "mass_kg", "wheels", w.mass_kg);
  w.friction = r.positive(wheels, "friction", "wheels", w.friction);
  w.wheelbase_m = r.positive(wheels, "wheelbase_m", "wheels", w.wheelbase_m);
  w.track_m = r.positive(wheels, "track_m", "wheels", w.track_m);
  w.max_torque_nm = r.positive(wheels, "max_torque_nm", "wheels", w.max_torque_nm);
  w.max_speed_radps = r.positive(wheels, "max_speed_radps", "wheels", w.max_speed_radps);
  if (w.track_m <= w.width_m) r.fail(wheels["track_m"], "wheels.track_m", "must be wider than a wheel");
  if (w.radius_m <= d.chassis.clearance_m)
    r.fail(wheels["radius_m"], "wheels.radius_m", "must exceed chassis.clearance_m");

  const YAML::Node control = root["control"];
  if (!control) r.fail(root, "control", "missing: which panel controls drive the robot");
  r.only_keys(control, "control", {"linear", "angular", "enable", "speed_scale", "estop"});
  if (!control["linear"]) r.fail(control, "control.linear", "missing");
  if (!control["angular"]) r.fail(control, "control.angular", "missing");
  d.control.linear = parse_axis(r, control["linear"], "control.linear");
  d.control.angular = parse_axis(r, control["angular"], "control.angular");
  if (const YAML::Node e = control["enable"]) {
    r.only_keys(e, "control.enable", {"switch", "position"});
    if (!e["switch"] || !e["position"]) r.fail(e, "control.enable", "needs switch and position");
    d.control.enable = std::make_pair(r.as<std::string>(e["switch"], "control.enable.switch"),
                                      r.as<std::string>(e["position"], "control.enable.position"));
  }
  if (const YAML::Node s = control["speed_scale"]) {
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
    d.control.speed_scale = std::make_pair(r.as<std::string>(s["switch"], "control.speed_scale.switch"), scale);
  }
  if (const YAML::Node e = control["estop"]) {
    r.only_keys(e, "control.estop", {"button"});
    if (!e["button"]) r.fail(e, "control.estop.button", "missing");
    d.control.estop_button = r.as<std::string>(e["button"], "control.estop.button");
  }
  return d;
}

RobotDescription load_robot_description(const std::string& path) {
  return parse_robot_description(read_text_file(path), path);
}

}  // namespace rise::sim
