// The Task Builder in Chromium (tests/instructor/browser/task_builder_check.cjs)
// against a real `rise-instructor serve --designs` on a copy of the shipped
// approach_object.yaml, laid out as the source tree so its ../../robots
// paths resolve: the page places the start, a new region by dragging and a
// reach_region event on it, saves, and "Try it" runs the saved file in
// rise-sim with rise-trainer run-task while the check drives the robot with
// the virtual panel page into the region; the report on the page and the
// report file score the new event, and the saved file passes
// `rise-trainer check`; a second try stopped from the page ends with
// rise-trainer's report (interrupted).

#include <catch2/catch.hpp>

#include "browser_support.hpp"

using namespace rise::instructor_test;
using rise::process::ChildProcess;

namespace {

// scratch/sim/training/examples holds a copy of the shipped tasks; the
// folders they name are links to the source tree's.
fs::path task_designs(const fs::path& dir) {
  const fs::path designs = dir / "sim" / "training" / "examples";
  fs::create_directories(designs);
  fs::create_directories(dir / "instructor");
  for (const char* d : {"sim/robots", "sim/worlds", "panels", "instructor/scenarios"})
    fs::create_directory_symlink(kSource + "/" + d, dir / d);
  for (const auto& e : fs::directory_iterator(kSource + "/sim/training/examples"))
    fs::copy_file(e.path(), designs / e.path().filename());
  return designs;
}

}  // namespace

TEST_CASE("the Task Builder places a region and an event by mouse, saves, and its try-it scores the event driven "
          "through the virtual panel", "[instructor][task_builder]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  char tmpl[] = "/tmp/rise-task-builder-test-XXXXXX";
  const fs::path dir = ::mkdtemp(tmpl);
  const fs::path designs = task_designs(dir);
  const std::string file = (designs / "approach_object.yaml").string();
  BuilderServer server(dir, designs);
  INFO(read_file((dir / "server.log").string()));
  REQUIRE(server.up);

  const std::string screens = screens_dir();
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/task_builder_check.cjs", server.base(),
                     server.token, screens, kWeb},
                    (dir / "task_check.log").string());
  const int node_code = node.wait_for(180000);
  if (node_code < 0) node.stop();
  const auto r = read_result((dir / "task_check.log").string());
  INFO(read_file((dir / "task_check.log").string()));
  const fs::path sandbox_dir = fs::temp_directory_path() / ("rise-task-builder-" + std::to_string(server.process.pid()));
  INFO(read_file((sandbox_dir / "try-1" / "trainer.log").string()));
  REQUIRE(node_code == 0);
  REQUIRE_FALSE(r.isMember("error"));
  CHECK(r["page_errors"].size() == 0);
  CHECK(r["status"].asInt() == 200);
  CHECK(r["opened"].asString() == "ok");
  // The kinds offered are the executor's, in the loader's order.
  CHECK(text(r["kinds"]) == text(parse_json(R"(["reach_region","time_exceeded","object_in_region","touch_object",)"
                                            R"("robot_damaged","robot_disabled","neutralize_object","collision"])")));
  CHECK(r["nav"].size() == 6);
  // The start pose: dragged 0.2 m back and 0.15 m aside, turned to 45° by its knob.
  CHECK(r["start_dragged"]["x"].asDouble() == Approx(3.8).margin(0.06));
  CHECK(r["start_dragged"]["y"].asDouble() == Approx(-0.15).margin(0.06));
  CHECK(r["start_turned"]["yaw_deg"].asDouble() == Approx(45).margin(3));
  // The new region as dragged (4.3, 0.1) → (5.0, 0.8), its corner then to (5.2, 1.0).
  REQUIRE(r["regions"].size() == 2);
  const auto& zone = r["regions"][1];
  CHECK(zone["name"].asString() == "drill_zone");
  CHECK(zone["min"][0].asDouble() == Approx(4.3).margin(0.06));
  CHECK(zone["min"][1].asDouble() == Approx(0.1).margin(0.06));
  CHECK(zone["max"][0].asDouble() == Approx(5.2).margin(0.06));
  CHECK(zone["max"][1].asDouble() == Approx(1.0).margin(0.06));
  // The taken name: the loader's error inline, with its key and the line of that event in the YAML.
  REQUIRE(r["duplicate_errors"].size() == 1);
  CHECK(r["duplicate_errors"][0]["key"].asString() == "events[4].name");
  CHECK(r["duplicate_errors"][0]["text"].asString().find("duplicate event name 'near_object'") != std::string::npos);
  CHECK(r["duplicate_yaml_line"].asString().find("{name: near_object, kind: touch_object") != std::string::npos);
  CHECK(text(r["end_on"]) == text(parse_json(R"(["object_touched","in_drill_zone"])")));

  // The saved file: what the page showed, and rise-trainer loads it.
  const std::string saved = read_file(file);
  CHECK(saved == r["yaml"].asString());
  CHECK(saved.find("  - {name: in_drill_zone, kind: reach_region, region: drill_zone, points: 7}") != std::string::npos);
  CHECK(saved.find("time_limit_s: 60\n") != std::string::npos);
  // The threshold edited in the form, in its place.
  CHECK(r["edit_form"]["kind"].asString() == "time_exceeded");
  CHECK(r["edit_form"]["after_s"].asString() == "20");
  CHECK(text(r["events"]) ==
        text(parse_json(R"(["near_object","object_touched","slow","bump","in_drill_zone"])")));
  CHECK(saved.find("  - {name: slow, kind: time_exceeded, after_s: 25, points: -5}") != std::string::npos);
  CHECK(saved.find("yaw_deg: 36.87}") != std::string::npos);
  CHECK(saved.find("# Mission 1 of the example training") == 0);
  const auto checked = trainer_check(dir, file, {});
  INFO(checked.second);
  CHECK(checked.first == 0);
  CHECK(checked.second.find("task approach_object, 5 events: ok") != std::string::npos);

  // Try it: rise-trainer run-task on the saved file scored the new event,
  // which ended the task (end_on), after the robot was driven from the panel page.
  CHECK(r["panel_url"].asString().find("panel.html?id=sandbox-") != std::string::npos);
  const auto& report = r["report"];
  REQUIRE(report.isObject());
  CHECK(report["end_reason"].asString().find("in_drill_zone") != std::string::npos);
  bool scored = false;
  for (const auto& e : report["events"]) scored |= e["name"].asString() == "in_drill_zone" && e["points"].asInt() == 7;
  CHECK(scored);
  CHECK(report["score"].asInt() >= 7);
  bool shown = false;
  for (const auto& row : r["report_rows"]) shown |= row.asString() == "in_drill_zone";
  CHECK(shown);
  CHECK(r["report_html_status"].asInt() == 200);
  const auto file_report = parse_json(read_file((sandbox_dir / "try-1" / "task_approach_object.json").string()));
  CHECK(file_report["counts"]["in_drill_zone"].asInt() == 1);
  CHECK(file_report["time_limit_s"].asDouble() == 60);
  CHECK(is_png(screens + "/task_builder.png"));
  // Stopped from the page: rise-trainer ended the task, its report shown.
  CHECK(r["stopped_report"]["end_reason"].asString() == "interrupted");
  CHECK(r["stopped_report"]["counts"]["in_drill_zone"].asInt() == 0);
  CHECK(r["stopped_state"].asString().rfind("ended", 0) == 0);
  CHECK(parse_json(read_file((sandbox_dir / "try-2" / "task_approach_object.json").string()))["end_reason"].asString() ==
        "interrupted");
  server.process.stop();
  fs::remove_all(dir);
  fs::remove_all(sandbox_dir);
}
