// The task YAML writer (the Task Builder saves through it): load → write →
// load gives the same task, scored the same, for every shipped task file,
// with its comments; names and comments that need quoting read back as
// written; and the kinds' table is what the loader enforces.

#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <regex>

#include "panels/yaml_reader.hpp"
#include "sim/training/task_description.hpp"
#include "sim/training/task_writer.hpp"
#include "tests/training/training_files.hpp"

using namespace rise::sim::training;
using rise::test::src;
namespace fs = std::filesystem;

namespace {

void check_same_event(const TaskEventSpec& a, const TaskEventSpec& b) {
  INFO("event " << a.name);
  CHECK(a.name == b.name);
  CHECK(a.kind == b.kind);
  CHECK(a.points == b.points);
  CHECK(a.max_count == b.max_count);
  CHECK(a.region == b.region);
  CHECK(a.object == b.object);
  CHECK(a.after_s == b.after_s);
  CHECK(a.hold_s == b.hold_s);
  CHECK(a.within_m == b.within_m);
  CHECK(a.per_second == b.per_second);
  CHECK(a.except == b.except);
  CHECK(a.comment == b.comment);
}

// What a task means: its files, start, limit, regions, events, end and
// success conditions and the comments; not the lines they sit on.
void check_same_task(const TaskDescription& a, const TaskDescription& b) {
  CHECK(a.name == b.name);
  CHECK(a.title == b.title);
  CHECK(a.comment == b.comment);
  CHECK(a.key_comments == b.key_comments);
  CHECK(a.robot_file == b.robot_file);
  CHECK(a.world_file == b.world_file);
  CHECK(a.panel_file == b.panel_file);
  CHECK(a.console_script == b.console_script);
  CHECK(a.scenario_file == b.scenario_file);
  REQUIRE(a.start.has_value() == b.start.has_value());
  if (a.start) {
    CHECK(a.start->xy_m == b.start->xy_m);
    CHECK(a.start->yaw_rad == Approx(b.start->yaw_rad).epsilon(1e-12));
  }
  CHECK(a.time_limit_s == b.time_limit_s);
  REQUIRE(a.regions.size() == b.regions.size());
  for (std::size_t i = 0; i < a.regions.size(); ++i) {
    CHECK(a.regions[i].name == b.regions[i].name);
    CHECK(a.regions[i].min_m == b.regions[i].min_m);
    CHECK(a.regions[i].max_m == b.regions[i].max_m);
    CHECK(a.region_comments[i] == b.region_comments[i]);
  }
  REQUIRE(a.events.size() == b.events.size());
  for (std::size_t i = 0; i < a.events.size(); ++i) check_same_event(a.events[i], b.events[i]);
  CHECK(a.end_on == b.end_on);
  CHECK(a.success == b.success);
}

std::vector<std::string> shipped_tasks() {
  std::vector<std::string> out;
  static const std::regex task_key("(^|\n)task:");
  for (const auto& e : fs::directory_iterator(src("sim/training/examples")))
    if (e.path().extension() == ".yaml" && std::regex_search(rise::panels::read_text_file(e.path().string()), task_key))
      out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("every shipped task file keeps its meaning through write and load", "[training][task_writer]") {
  const auto files = shipped_tasks();
  REQUIRE(files.size() >= 3);
  for (const auto& file : files) {
    INFO(file);
    const TaskDescription original = load_task_description(file);
    TaskYamlLines lines;
    const std::string text = write_task_description(original, &lines);
    INFO(text);
    // Written beside the original, so its paths resolve the same.
    const TaskDescription again = parse_task_description(text, file);
    check_same_task(original, again);
    CHECK(write_task_description(again) == text);  // a fixed point
    for (std::size_t i = 0; i < again.events.size(); ++i) CHECK(again.events[i].line == lines.events[i]);
    for (std::size_t i = 0; i < again.regions.size(); ++i) CHECK(again.region_lines[i] == lines.regions[i]);
  }
}

TEST_CASE("a task's comments survive a save", "[training][task_writer]") {
  const auto t = load_task_description(src("sim/training/examples/approach_object.yaml"));
  CHECK(t.comment.rfind("Mission 1 of the example training", 0) == 0);
  CHECK(t.key_comments.at("scenario") == "rise-instructor scenario --task this file");
  CHECK(t.robot_path == "../../robots/tracked_eod.yaml");
  const std::string text = write_task_description(t);
  CHECK(text.find("# Mission 1 of the example training") == 0);
  CHECK(text.find("# rise-instructor scenario --task this file\n") != std::string::npos);
  CHECK(text.find("  - {name: near_object, kind: reach_region, region: near_object, points: 10}") != std::string::npos);
  CHECK(text.find("start: {xy_m: [4, 0], yaw_deg: 36.87}") != std::string::npos);
}

TEST_CASE("names and comments that need quoting read back as written", "[training][task_writer]") {
  auto t = load_task_description(src("sim/training/examples/metro_transport.yaml"));
  t.title = "Übung: \"night\" #2";
  t.comment = "first\n\nthird: with # and 'quotes'";
  t.events[0].comment = "a # in a comment\nand a second line";
  t.events[0].max_count = 3;
  t.regions.push_back({"box: 1", {0, 0, 0}, {1, 1, 1}});
  t.region_comments.push_back("'new'");
  const std::string text = write_task_description(t);
  INFO(text);
  const auto again = parse_task_description(text, t.file);
  CHECK(again.title == t.title);
  CHECK(again.comment == t.comment);
  CHECK(again.events[0].comment == "a # in a comment and a second line");
  CHECK(again.events[0].max_count == 3);
  CHECK(again.regions.back().name == "box: 1");
  CHECK(again.region_comments.back() == "'new'");
}

TEST_CASE("the kinds' table is what the loader takes and refuses", "[training][task_writer]") {
  const std::string head = rise::test::task_header("k", "{xy_m: [0, 0]}", 10);
  for (const auto& info : task_event_kinds()) {
    INFO(info.name);
    CHECK(task_event_kind(info.name) == info.kind);
    // Every key it lists is taken (names the world has, numbers > 0) ...
    std::string entry = "  - {name: e, kind: " + std::string(info.name);
    for (const auto& p : info.params) {
      const std::string type = p.type;
      entry += std::string(", ") + p.key + ": " +
               (type == "region" ? "near_object" : type == "object" ? "hazardous_object" : type == "per" ? "second"
                : type == "names" ? "[hazardous_object]" : "1.5");
    }
    const auto t = parse_task_description(head + "regions:\n  - {name: near_object, min: [0, 0, 0], max: [1, 1, 1]}\n"
                                                 "events:\n" + entry + "}\n",
                                          "k.yaml");
    CHECK(t.events[0].max_count == info.default_max_count);
    // ... and a key it does not list is refused with its line and key.
    for (const char* key : {"region", "after_s", "per"}) {
      if (std::any_of(info.params.begin(), info.params.end(), [&](const auto& p) { return p.key == std::string(key); }))
        continue;
      const std::string bad = head + "events:\n" + entry + ", " + key + ": 1}\n";
      CHECK_THROWS_WITH(parse_task_description(bad, "k.yaml"),
                        Catch::Contains("k.yaml:8: events[0]." + std::string(key) + ": not for kind " + info.name));
    }
  }
}
