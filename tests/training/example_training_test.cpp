#include <catch2/catch.hpp>

#include <cstdio>

#include "sim/app/scripted_console.hpp"
#include "sim/training/task_description.hpp"

using namespace rise::sim::training;

namespace {
std::string src(const std::string& p) { return std::string(RISE_SOURCE_DIR) + "/" + p; }
}  // namespace

TEST_CASE("the metro transport script pushes the hazardous object into the neutralization area", "[training]") {
  const auto task = load_task_description(src("sim/training/examples/metro_transport.yaml"));
  rise::trainer::ScriptedConsole console(task.panel_file, task.console_script);
  const auto r = rise::trainer::play_task(task, &console);
  for (const auto& e : r.events) UNSCOPED_INFO(e.time_s << " " << e.name << " " << e.points << " " << e.detail);
  if (!r.object_tracks.empty()) {
    const auto& t = r.object_tracks.begin()->second.back();
    UNSCOPED_INFO("object at " << t.x_m << " " << t.y_m);
  }
  UNSCOPED_INFO("robot at " << r.trajectory.back().x_m << " " << r.trajectory.back().y_m << " end " << r.end_reason);
  CHECK(r.success);
  CHECK(r.counts.at("object_delivered") == 1);
  CHECK(r.score >= 20);
}

TEST_CASE("the example missions' scripts achieve them", "[training]") {
  for (const char* f : {"sim/training/examples/approach_object.yaml", "sim/training/examples/neutralize_object.yaml"}) {
    const auto task = load_task_description(src(f));
    rise::trainer::ScriptedConsole console(task.panel_file, task.console_script);
    const auto r = rise::trainer::play_task(task, &console);
    for (const auto& e : r.events) UNSCOPED_INFO(e.time_s << " " << e.name << " " << e.points << " " << e.detail);
    UNSCOPED_INFO(f << " end " << r.end_reason << " score " << r.score);
    CHECK(r.success);
    CHECK(r.score >= 20);
  }
}
