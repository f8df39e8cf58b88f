#include <catch2/catch.hpp>

#include "instructor/scenario.hpp"
#include "instructor/scenario_runner.hpp"
#include "sim/training/task_description.hpp"

using namespace rise::instructor;

namespace {
std::string error_of(const std::string& text) {
  try {
    parse_scenario(text, "s.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}
const char* kScenario = R"(scenario: test
seed: 4
faults:
  - {id: a, kind: stuck_at, target: drive_y, value: 0.5, at: 1.0, duration: 2.0}
  - {id: b, kind: motor_failure, target: left, on: {event: region_entered, b: zone}, delay: 0.5}
  - {id: c, kind: noise, target: drive_x, value_range: [0.1, 0.3], when: {field: speed_mps, above: 0.4},
     clear_on: {on: {event: region_left}}}
  - {id: d, kind: can_drop, target: console, value: 0.2, at: 0.5, jitter: 2.0, probability: 0.5}
)";
}  // namespace

TEST_CASE("the shipped scenario loads and the example task names it", "[instructor]") {
  const Scenario s = load_scenario(std::string(RISE_SOURCE_DIR) + "/instructor/scenarios/approach_trouble.yaml");
  CHECK(s.name == "approach-trouble");
  CHECK(s.seed == 7);
  REQUIRE(s.faults.size() == 4);
  CHECK(s.faults[1].trigger.kind == Trigger::Kind::Event);
  CHECK(s.faults[2].trigger.kind == Trigger::Kind::Condition);
  const auto task = rise::sim::training::load_task_description(std::string(RISE_SOURCE_DIR) +
                                                              "/sim/training/examples/approach_object.yaml");
  CHECK_THAT(task.scenario_file, Catch::EndsWith("instructor/scenarios/approach_trouble.yaml"));
}

TEST_CASE("scenario mistakes are refused with file:line and key", "[instructor]") {
  CHECK(error_of("scenario: x\nfaults:\n  - {id: a, kind: melt, target: y, at: 1}\n") ==
        "s.yaml:3: faults[0].kind: unknown fault kind 'melt'");
  CHECK(error_of("scenario: x\nfaults:\n  - {id: a, kind: noise, target: y}\n") ==
        "s.yaml:3: faults[0]: no trigger: give at, on or when");
  CHECK(error_of("scenario: x\nfaults:\n  - {id: a, kind: noise, at: 1, when: {field: x_m, above: 1}}\n") ==
        "s.yaml:3: faults[0]: one trigger of at, on, when");
  CHECK_THAT(error_of("scenario: x\nfaults:\n  - {id: a, kind: noise, at: 1}\n  - {id: a, kind: noise, at: 2}\n"),
             Catch::StartsWith("s.yaml:4: faults[1].id:"));
  CHECK_THAT(error_of("scenario: x\nfaults:\n  - {id: a, kind: noise, at: 1, dureation: 2}\n"),
             Catch::StartsWith("s.yaml:3: faults[0].dureation: unknown key"));
  CHECK_THAT(error_of("scenario: x\nfaults:\n  - {id: a, kind: noise, when: {field: pressure, above: 1}}\n"),
             Catch::Contains("faults[0].when.field: unknown field 'pressure'"));
  CHECK_THAT(error_of("scenario: x\nfaults:\n  - {id: a, kind: noise, at: 1, probability: 2}\n"),
             Catch::Contains("faults[0].probability: must be 0..1"));
  CHECK_THAT(error_of("scenario: x\nfaults:\n  - {id: a, kind: noise, at: -1}\n"), Catch::Contains("faults[0].at: must be >= 0"));
  CHECK_THAT(error_of("faults: [{id: a, kind: noise, at: 1}]\n"), Catch::Contains("scenario: missing"));
}

TEST_CASE("a scenario runner fires on time, on events and on conditions, and clears on its triggers", "[instructor]") {
  ScenarioRunner r(parse_scenario(kScenario, "s.yaml"), 4);
  CHECK(r.advance(0.9).size() <= 1);  // only d may be due (jitter)
  std::vector<ScenarioAction> all;
  const auto take = [&](std::vector<ScenarioAction> v) {
    for (auto& a : v) all.push_back(std::move(a));
  };
  for (double t = 0.0; t <= 3.0; t += 0.01) take(r.advance(t));
  const auto find = [&](const std::string& id, bool inject) -> const ScenarioAction* {
    for (const auto& a : all)
      if (a.id == id && a.inject == inject) return &a;
    return nullptr;
  };
  REQUIRE(find("a", true));
  CHECK(find("a", true)->time_s == 1.0);
  CHECK(find("a", true)->duration_s == 2.0);
  CHECK(find("b", true) == nullptr);
  take(r.on_event(3.1, "region_entered", "t1", "elsewhere"));
  CHECK(find("b", true) == nullptr);
  take(r.on_event(3.2, "region_entered", "t1", "zone"));
  CHECK(find("b", true) == nullptr);  // 0.5 s delay
  take(r.advance(3.7));
  REQUIRE(find("b", true));
  CHECK(find("b", true)->time_s == Approx(3.7));
  take(r.on_observation(4.0, {{"speed_mps", 0.3}}));
  CHECK(find("c", true) == nullptr);
  take(r.on_observation(4.1, {{"speed_mps", 0.5}}));
  REQUIRE(find("c", true));
  CHECK(find("c", true)->value >= 0.1);
  CHECK(find("c", true)->value <= 0.3);
  CHECK_FALSE(r.finished(4.2));
  take(r.on_event(4.5, "region_left", "t1", "zone"));
  CHECK(find("c", false));
  const auto end = r.finish(5.0);
  // b (and d, when its draw fired it) have no duration: the scenario's end
  // clears them (auto_clear); a ended on its own, c was cleared by its trigger.
  std::vector<std::string> cleared;
  for (const auto& e : end) {
    CHECK_FALSE(e.inject);
    cleared.push_back(e.id);
  }
  std::vector<std::string> expected{"b"};
  if (find("d", true)) expected.push_back("d");
  CHECK(cleared == expected);
  CHECK(r.finished(5.0));
}

TEST_CASE("a scenario's random draws depend on the seed only", "[instructor]") {
  const auto run = [](uint64_t seed) {
    ScenarioRunner r(parse_scenario(kScenario, "s.yaml"), seed);
    std::vector<std::pair<double, double>> out;  // (time, value) of every injection
    r.on_observation(0.0, {{"speed_mps", 1.0}});
    for (int i = 0; i <= 300; ++i)
      for (const auto& a : r.advance(i * 0.01)) out.emplace_back(a.time_s, a.value + static_cast<double>(a.seed % 1000));
    return out;
  };
  CHECK(run(4) == run(4));
  bool any_differs = false;
  for (uint64_t seed = 5; seed < 10; ++seed) any_differs = any_differs || run(seed) != run(4);
  CHECK(any_differs);
  // probability 0.5 over many seeds: d fires for some, not for others.
  int fired = 0;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    ScenarioRunner r(parse_scenario(kScenario, "s.yaml"), seed);
    for (int i = 0; i <= 300; ++i)
      for (const auto& a : r.advance(i * 0.01)) fired += a.id == "d";
  }
  CHECK(fired > 5);
  CHECK(fired < 35);
}

TEST_CASE("an action becomes an unsigned FaultCommand with every field", "[instructor]") {
  const ScenarioAction a{1.5, true, "x", "drift", "drive_y", 0.1, 0.2, 3.0, 99};
  const auto c = to_command(a, "t7", "instructor");
  CHECK(c.trainee_id == "t7");
  CHECK(c.action == "inject");
  CHECK(c.fault_id == "x");
  CHECK(c.kind == "drift");
  CHECK(c.rate == 0.2);
  CHECK(c.duration_s == 3.0);
  CHECK(c.seed == 99);
  CHECK(c.signature_len == 0);
}
