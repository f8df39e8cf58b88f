#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "sim/app/scripted_console.hpp"
#include "sim/training/report.hpp"
#include "tests/training/training_files.hpp"

using namespace rise::sim::training;
using rise::test::src;
using Catch::Matchers::Contains;

namespace {

// The metro transport, played in-process with its scripted console.
const TaskResult& transport_result() {
  static const TaskResult r = [] {
    const auto task = load_task_description(src("sim/training/examples/metro_transport.yaml"));
    rise::trainer::ScriptedConsole console(task.panel_file, task.console_script);
    auto x = rise::trainer::play_task(task, &console);
    x.node = "mission3";
    x.attempt = 2;
    return x;
  }();
  return r;
}

bool have_chromium() { return std::system("command -v chromium >/dev/null 2>&1") == 0; }

}  // namespace

TEST_CASE("a task result survives its JSON round trip", "[training]") {
  const auto& r = transport_result();
  REQUIRE(r.success);
  const auto back = task_result_from_json(task_result_json(r));
  CHECK(back.task == r.task);
  CHECK(back.node == "mission3");
  CHECK(back.attempt == 2);
  CHECK(back.score == r.score);
  CHECK(back.time_s == r.time_s);
  CHECK(back.success == r.success);
  CHECK(back.end_reason == r.end_reason);
  CHECK(back.counts == r.counts);
  REQUIRE(back.events.size() == r.events.size());
  CHECK(back.events.back().detail == r.events.back().detail);
  REQUIRE(back.trajectory.size() == r.trajectory.size());
  CHECK(back.trajectory.back().x_m == r.trajectory.back().x_m);
  CHECK(back.object_tracks.at("hazardous_object").size() == r.object_tracks.at("hazardous_object").size());
  CHECK_THROWS_WITH(task_result_from_json("{\"task\": \"x\"}"), Contains("key 'score' missing"));
  CHECK_THROWS_WITH(task_result_from_json("{\"task\""), Contains("not JSON"));
}

TEST_CASE("reports are written atomically: the old file or the new one, no temporary left", "[training]") {
  const auto dir = rise::test::temp_dir("atomic");
  const auto path = dir + "/report.json";
  write_file_atomically(path, "first");
  write_file_atomically(path, "second");
  CHECK(rise::test::read_file(path) == "second");
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file() ? 1 : 0;
  CHECK(files == 1);
  CHECK_THROWS_WITH(write_file_atomically(dir + "/no/such/dir/r.json", "x"), Contains("no/such/dir/r.json.tmp"));
}

TEST_CASE("the journal keeps every entry and drops a line torn by a kill", "[training]") {
  const auto dir = rise::test::temp_dir("journal");
  const auto path = dir + "/journal.jsonl";
  CHECK(read_journal(path).empty());
  append_journal(path, {"training_started", "fig10", "t1", "", 0, std::nullopt, "x.yaml"});
  append_journal(path, {"task_started", "fig10", "t1", "mission1", 1, std::nullopt, ""});
  append_journal(path, {"task_finished", "fig10", "t1", "mission1", 1, transport_result(), ""});
  {
    std::ofstream torn(path, std::ios::app);
    torn << "{\"type\":\"task_started\",\"node\":\"miss";  // the writer died here
  }
  const auto entries = read_journal(path);
  REQUIRE(entries.size() == 3);
  CHECK(entries[1].node == "mission1");
  REQUIRE(entries[2].result);
  CHECK(entries[2].result->score == transport_result().score);
  CHECK(entries[2].result->trajectory.size() == transport_result().trajectory.size());
  // A bad line that is not the last one is an error, not silently skipped.
  const auto bad = dir + "/bad.jsonl";
  rise::test::write_file(dir, "bad.jsonl", "{\"type\":\"training_started\"}\nnot json\n{\"type\":\"task_started\"}\n");
  CHECK_THROWS_WITH(read_journal(bad), Contains(bad + ":2: not JSON"));
}

TEST_CASE("the HTML report holds the trajectory plot over the world map and the event timeline", "[training]") {
  const auto& r = transport_result();
  const auto world = rise::sim::load_world_description(src("sim/worlds/building.yaml"));
  const auto html = task_report_html(r, world);
  CHECK_THAT(html, Contains("<svg id=\"map\""));
  CHECK_THAT(html, Contains(std::string("id=\"trajectory\" stroke=\"") + kTrajectoryColour));
  CHECK_THAT(html, Contains("<title>region neutralization_area</title>"));
  CHECK_THAT(html, Contains("<title>door door_ab</title>"));
  CHECK_THAT(html, Contains("<svg id=\"timeline\""));
  CHECK_THAT(html, Contains("<td>object_delivered</td>"));
  TrainingReport t{"fig10_metro", "t", "f.yaml", "t1", {{"mission3", 2, r, "always → END"}}, true, "END reached", r.score, {"01_mission3_2.html"}};
  const auto th = training_report_html(t);
  CHECK_THAT(th, Contains("<a href=\"01_mission3_2.html\">metro_transport</a>"));
  CHECK_THAT(training_report_json(t), Contains("\"transition\" : \"always → END\""));
}

TEST_CASE("the HTML report renders in headless Chromium with the trajectory drawn in the plot", "[training]") {
  if (!have_chromium()) {
    WARN("skipped: chromium is not installed (run.sh installs Debian's chromium)");
    return;
  }
  const auto dir = rise::test::temp_dir("chromium");
  const auto world = rise::sim::load_world_description(src("sim/worlds/building.yaml"));
  write_file_atomically(dir + "/task.html", task_report_html(transport_result(), world));
  const std::string png = dir + "/shot.png";
  const std::string cmd = "chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --screenshot=" + png +
                          " --window-size=1000,1100 file://" + dir + "/task.html >" + dir + "/chromium.log 2>&1";
  const int rc = std::system(cmd.c_str());
  INFO(rise::test::read_file(dir + "/chromium.log"));
  REQUIRE(WIFEXITED(rc));
  REQUIRE(WEXITSTATUS(rc) == 0);
  const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);  // BGR
  REQUIRE(!img.empty());
  CHECK(img.cols == 1000);
  // The plot area: the bounding box of the map's #fafafa background.
  int x0 = img.cols, y0 = img.rows, x1 = -1, y1 = -1;
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const auto p = img.at<cv::Vec3b>(y, x);
      if (p[0] == 250 && p[1] == 250 && p[2] == 250) {
        x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
      }
    }
  REQUIRE(x1 > x0 + 300);
  REQUIRE(y1 > y0 + 200);
  // kTrajectoryColour #d62728 = RGB (214, 39, 40), inside the plot.
  int stroke = 0, outside = 0;
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const auto p = img.at<cv::Vec3b>(y, x);
      if (std::abs(p[2] - 214) <= 6 && std::abs(p[1] - 39) <= 6 && std::abs(p[0] - 40) <= 6)
        ++(x >= x0 && x <= x1 && y >= y0 && y <= y1 ? stroke : outside);
    }
  CAPTURE(x0, y0, x1, y1, stroke, outside);
  CHECK(stroke > 300);  // a 4 px line about 3.7 m long at ~60 px/m
  CHECK(outside == 0);
}
