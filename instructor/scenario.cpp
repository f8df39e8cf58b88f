#include "instructor/scenario.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "panels/yaml_reader.hpp"

namespace rise::instructor {
namespace {

Trigger parse_trigger(const panels::YamlReader& r, const YAML::Node& item, const std::string& where, bool clear) {
  Trigger t;
  const char* at_key = "at";
  const YAML::Node node = clear ? item["clear_on"] : item;
  const std::string base = clear ? where + ".clear_on" : where;
  if (clear) {
    if (!node) return t;
    r.only_keys(node, base, {"at", "on", "when"});
  }
  int count = 0;
  if (node[at_key]) {
    ++count;
    t.kind = Trigger::Kind::At;
    t.at_s = r.positive(node, at_key, base, 0.0, true);
  }
  if (const YAML::Node on = node["on"]) {
    ++count;
    t.kind = Trigger::Kind::Event;
    r.only_keys(on, base + ".on", {"event", "a", "b"});
    if (!on["event"]) r.fail(on, base + ".on.event", "missing");
    t.event = r.as<std::string>(on["event"], base + ".on.event");
    if (on["a"]) t.a = r.as<std::string>(on["a"], base + ".on.a");
    if (on["b"]) t.b = r.as<std::string>(on["b"], base + ".on.b");
  }
  if (const YAML::Node when = node["when"]) {
    ++count;
    t.kind = Trigger::Kind::Condition;
    const std::string k = base + ".when";
    r.only_keys(when, k, {"field", "above", "below"});
    if (!when["field"]) r.fail(when, k + ".field", "missing");
    t.field = r.as<std::string>(when["field"], k + ".field");
    static const std::set<std::string> fields = {"speed_mps", "x_m", "y_m", "damage", "failsafe", "sim_time_s"};
    if (!fields.count(t.field))
      r.fail(when["field"], k + ".field", "unknown field '" + t.field + "' (speed_mps, x_m, y_m, damage, failsafe, sim_time_s)");
    if (when["above"]) t.above = r.as<double>(when["above"], k + ".above");
    if (when["below"]) t.below = r.as<double>(when["below"], k + ".below");
    if (!t.above && !t.below) r.fail(when, k, "needs above: or below:");
  }
  if (count > 1) r.fail(node, base, "one trigger of at, on, when");
  if (count == 0 && !clear) r.fail(item, where, "no trigger: give at, on or when");
  return t;
}

}  // namespace

const std::vector<std::string>& fault_kinds() {
  static const std::vector<std::string> kinds = {
      "stuck_at", "offset", "drift", "noise", "out_of_range", "intermittent", "disconnect",   // input
      "can_drop", "can_delay", "can_corrupt", "can_bus_off", "modbus_exception", "modbus_timeout",  // wire
      "lcm_loss", "lcm_latency",                                                                   // transport
      "motor_failure", "motor_weakness", "track_slip", "weak_joint",                               // physics
      "camera_blackout", "scanner_noise", "scanner_dropout"};                                      // sensor
  return kinds;
}

Scenario parse_scenario(const std::string& text, const std::string& file) {
  panels::YamlReader r(file);
  const YAML::Node root = r.load_text(text);
  if (!root || root.IsNull()) throw std::runtime_error(file + ":1: empty scenario");
  r.only_keys(root, "", {"scenario", "seed", "faults"});
  Scenario s;
  s.file = file;
  if (!root["scenario"]) r.fail(root, "scenario", "missing");
  s.name = r.as<std::string>(root["scenario"], "scenario");
  if (root["seed"]) s.seed = r.as<uint64_t>(root["seed"], "seed");
  const YAML::Node faults = root["faults"];
  if (!faults || !faults.IsSequence() || faults.size() == 0) r.fail(faults ? faults : root, "faults", "expected a list of faults");
  std::set<std::string> ids;
  for (std::size_t i = 0; i < faults.size(); ++i) {
    const YAML::Node f = faults[i];
    const std::string where = "faults[" + std::to_string(i) + "]";
    r.only_keys(f, where, {"id", "kind", "target", "value", "value_range", "rate", "at", "on", "when", "delay",
                           "jitter", "probability", "duration", "clear_on", "auto_clear"});
    ScenarioFault sf;
    sf.line = f.Mark().line + 1;
    if (!f["id"]) r.fail(f, where + ".id", "missing");
    sf.id = r.as<std::string>(f["id"], where + ".id");
    if (sf.id.empty() || !ids.insert(sf.id).second) r.fail(f["id"], where + ".id", "'" + sf.id + "' is empty or used twice");
    if (!f["kind"]) r.fail(f, where + ".kind", "missing");
    sf.kind = r.as<std::string>(f["kind"], where + ".kind");
    const auto& kinds = fault_kinds();
    if (std::find(kinds.begin(), kinds.end(), sf.kind) == kinds.end())
      r.fail(f["kind"], where + ".kind", "unknown fault kind '" + sf.kind + "'");
    if (f["target"]) sf.target = r.as<std::string>(f["target"], where + ".target");
    if (f["value"]) sf.value = r.as<double>(f["value"], where + ".value");
    if (f["value_range"]) {
      if (f["value"]) r.fail(f["value_range"], where + ".value_range", "give value or value_range, not both");
      const auto range = r.vector<2>(f, "value_range", where);
      if (!(range[0] <= range[1])) r.fail(f["value_range"], where + ".value_range", "expected [low, high]");
      sf.value_range = range;
    }
    if (f["rate"]) sf.rate = r.as<double>(f["rate"], where + ".rate");
    sf.trigger = parse_trigger(r, f, where, false);
    sf.delay_s = r.positive(f, "delay", where, 0.0, true);
    sf.jitter_s = r.positive(f, "jitter", where, 0.0, true);
    sf.probability = r.positive(f, "probability", where, 1.0, true);
    if (sf.probability > 1.0) r.fail(f["probability"], where + ".probability", "must be 0..1");
    sf.duration_s = r.positive(f, "duration", where, 0.0, true);
    sf.clear_on = parse_trigger(r, f, where, true);
    if (f["auto_clear"]) sf.auto_clear = r.as<bool>(f["auto_clear"], where + ".auto_clear");
    s.faults.push_back(std::move(sf));
  }
  return s;
}

Scenario load_scenario(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  return parse_scenario(text.str(), path);
}

}  // namespace rise::instructor
