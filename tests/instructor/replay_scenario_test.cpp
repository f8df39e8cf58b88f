// One scenario, one seed, twice: the daemon's mapper (fed the console's
// firmware frames at explicit times) and the sim (stepped at 1 ms) under the
// same scenario give bit-identical PanelState and RobotState streams. In
// process, with the sim's clock as the scenario's: the same code paths
// rise-hild and rise-sim run, without the network's timing.

#include <catch2/catch.hpp>

#include <cstring>

#include "firmware_protocol/console_can.hpp"
#include "hil/fault_injector.hpp"
#include "hil/panel_mapper.hpp"
#include "hil/panel_state_message.hpp"
#include "instructor/scenario.hpp"
#include "instructor/scenario_runner.hpp"
#include "sim/simulation.hpp"

namespace fp = rise::firmware_protocol;
using namespace rise::instructor;

namespace {

const char* kScenario = R"(scenario: replay
seed: 3
faults:
  - {id: noisy, kind: noise, target: drive_y, value: 0.2, at: 0.2, jitter: 0.3, duration: 0.5}
  - {id: slow-left, kind: motor_weakness, target: left, value_range: [0.2, 0.8],
     on: {event: region_entered, b: zone}, duration: 0.6}
  - {id: stuck, kind: stuck_at, target: drive_x, value_range: [0.3, 0.9], when: {field: speed_mps, above: 0.5},
     duration: 0.3}
  - {id: maybe, kind: motor_failure, target: right, at: 0.8, probability: 0.5, duration: 0.2}
)";

struct Streams {
  std::vector<std::vector<uint8_t>> panel_states;  // encoded PanelState
  std::vector<std::vector<double>> robot_states;   // pose, twist, wheel rates
  std::vector<std::string> robot_faults;
  std::vector<std::string> actions;
};

rise::sim::ControlInput to_input(const rise::panels::PanelDefinition& def, const rise::hil::PanelSnapshot& s) {
  rise::sim::ControlInput in;
  in.fresh = true;
  in.failsafe = s.failsafe;
  in.deadman = s.deadman;
  for (std::size_t i = 0; i < def.controls.size(); ++i) {
    const auto& c = def.controls[i];
    if (c.kind == rise::panels::ControlKind::Axis) in.axes[c.name] = s.controls[i].axis;
    if (c.kind == rise::panels::ControlKind::Button) in.buttons[c.name] = s.controls[i].pressed;
    if (c.kind == rise::panels::ControlKind::Switch) {
      in.switches[c.name] = s.controls[i].position;
      in.switch_labels[c.name] = c.positions[s.controls[i].position];
    }
  }
  return in;
}

Streams run(uint64_t seed) {
  const auto def = rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) +
                                                       "/panels/definitions/rise_console.yaml");
  rise::hil::PanelMapper mapper(def);
  rise::sim::WorldDescription world;
  world.regions.push_back({"zone", {1.0, -3.0, -1.0}, {4.0, 3.0, 2.0}});
  rise::sim::Simulation sim(rise::sim::load_robot_description(std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml"),
                            world);
  ScenarioRunner runner(parse_scenario(kScenario, "replay.yaml"), seed);
  fp::Encoder encoder(0);
  Streams out;
  constexpr int64_t kT0 = 1'000'000;
  mapper.on_connection(0, true, kT0);

  const auto dispatch = [&](const std::vector<ScenarioAction>& actions, int64_t now_us) {
    for (const auto& a : actions) {
      out.actions.push_back(a.id + (a.inject ? " inject " : " clear ") + std::to_string(a.value));
      const auto kind = rise::sim::parse_sim_fault_kind(a.kind);
      if (!a.inject) {
        mapper.clear_input_faults(a.id, now_us);
        sim.clear_fault(0, a.id);
      } else if (kind) {
        rise::sim::PhysicsFault f;
        f.id = a.id;
        f.kind = *kind;
        f.target = a.target;
        f.value = a.value;
        f.seed = a.seed;
        f.duration_s = a.duration_s;
        REQUIRE(sim.set_fault(0, f).empty());
      } else {
        rise::hil::InputFault f;
        f.id = a.id;
        f.kind = *rise::hil::parse_input_fault_kind(a.kind);
        f.control = *def.find_control(a.target);
        f.value = a.value;
        f.rate = a.rate;
        f.seed = a.seed;
        f.start_us = now_us;
        f.end_us = now_us + static_cast<int64_t>(a.duration_s * 1e6);
        REQUIRE(mapper.inject_input_fault(f).empty());
      }
    }
  };

  for (int cycle = 0; cycle < 250; ++cycle) {  // 2.5 s, the console at 100 Hz
    const int64_t t = kT0 + cycle * 10'000;
    const double scenario_s = sim.time_s();
    const auto feed = [&](const fp::Message& m) {
      const auto w = encoder.next(m);
      mapper.on_frame(0, w.can_id, w.data, t);
    };
    feed(fp::HeartbeatFrame{fp::kProtocolVersion, fp::PanelStatus::Operational, static_cast<uint32_t>(t / 1000)});
    feed(fp::AxesFrame{0, {0, fp::axis_from_unit(1.0f), 0}});
    feed(fp::AxesFrame{1, {0, 0, 0}});
    feed(fp::ButtonsFrame{1});  // dead-man
    fp::SwitchesFrame sw;
    sw.position = {0, 2, 0, 0, 0, 0};  // drive, fast
    feed(sw);
    dispatch(runner.advance(scenario_s), t);
    const auto snap = mapper.evaluate(t);
    out.panel_states.emplace_back();
    const auto msg = rise::hil::to_message(def, snap, "t1", cycle, t, {"mem://replay"});
    out.panel_states.back().resize(static_cast<std::size_t>(msg.getEncodedSize()));
    msg.encode(out.panel_states.back().data(), 0, msg.getEncodedSize());
    sim.set_input(to_input(def, snap));
    for (int step = 0; step < 10; ++step) {
      sim.step();
      for (const auto& e : sim.take_events())
        dispatch(runner.on_event(sim.time_s(), rise::sim::to_string(e.kind), e.a, e.b), t);
    }
    const auto r = sim.snapshot();
    dispatch(runner.on_observation(sim.time_s(), {{"speed_mps", r.speed_mps()}, {"x_m", r.position_m[0]}}), t);
    std::vector<double> row(r.position_m.begin(), r.position_m.end());
    row.insert(row.end(), r.orientation_wxyz.begin(), r.orientation_wxyz.end());
    row.insert(row.end(), r.linear_velocity_mps.begin(), r.linear_velocity_mps.end());
    for (const auto& w : r.wheels) row.push_back(w.velocity_radps);
    out.robot_states.push_back(std::move(row));
    std::string faults;
    for (const auto& f : r.active_faults) faults += f + ";";
    out.robot_faults.push_back(faults);
  }
  return out;
}

}  // namespace

TEST_CASE("a scenario run twice with one seed gives identical PanelState and RobotState streams", "[instructor]") {
  const Streams a = run(3);
  const Streams b = run(3);
  REQUIRE(a.panel_states.size() == 250);
  CHECK(a.actions == b.actions);
  CHECK(a.panel_states == b.panel_states);
  CHECK(a.robot_states == b.robot_states);
  CHECK(a.robot_faults == b.robot_faults);

  // The scenario did act: the noise, the region trigger and the condition all fired.
  const auto fired = [&](const std::string& id) {
    for (const auto& s : a.actions)
      if (s.rfind(id + " inject", 0) == 0) return true;
    return false;
  };
  CHECK(fired("noisy"));
  CHECK(fired("slow-left"));
  CHECK(fired("stuck"));
  bool weak_seen = false;
  for (const auto& f : a.robot_faults) weak_seen = weak_seen || f.find("slow-left: motor_weakness left") != std::string::npos;
  CHECK(weak_seen);

  // Another seed draws other times and values: the streams differ.
  const Streams c = run(4);
  CHECK(c.actions != a.actions);
  CHECK(c.panel_states != a.panel_states);
}
