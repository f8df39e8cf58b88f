// rise-trainer over real LCM multicast (udpm, ttl=0, a port of this test's
// own) with real rise-sim processes: the executor beside a running sim, a
// training killed (kill -9) and resumed, two trainees at once.

#include <catch2/catch.hpp>
#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <set>

#include "msgs/channels.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/TaskEvent.hpp"
#include "rise_msgs/TaskStatus.hpp"
#include "sim/training/report.hpp"
#include "tests/training/training_files.hpp"

using namespace rise::sim::training;
using rise::process::ChildProcess;
using rise::test::src;

namespace {

const std::string kBin = std::string(RISE_BINARY_DIR) + "/bin/";
const std::string kLcm = "udpm://239.255.76.67:" + std::to_string(7800 + ::getpid() % 400) + "?ttl=0";

// What one trainee's executor said on LCM.
struct Heard {
  std::vector<rise_msgs::TaskEvent> events;
  std::vector<rise_msgs::TaskStatus> statuses;
  std::set<std::string> channels;
  void on_event(const lcm::ReceiveBuffer*, const std::string& ch, const rise_msgs::TaskEvent* m) {
    events.push_back(*m);
    channels.insert(ch);
  }
  void on_status(const lcm::ReceiveBuffer*, const std::string& ch, const rise_msgs::TaskStatus* m) {
    statuses.push_back(*m);
    channels.insert(ch);
  }
};

void listen(lcm::LCM& lcm, const std::string& id, Heard& h) {
  lcm.subscribe(rise::msgs::task_event_channel(id), &Heard::on_event, &h)->setQueueCapacity(1000);
  lcm.subscribe(rise::msgs::task_status_channel(id), &Heard::on_status, &h)->setQueueCapacity(1000);
}

// Handles LCM until `done` holds or every child in `watch` has exited (then
// false), at most limit_s.
bool until(lcm::LCM& lcm, const std::function<bool()>& done, std::vector<ChildProcess*> watch, double limit_s = 60) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    bool any = false;
    for (auto* c : watch) any = any || c->running();
    if (!any) {
      // The children's last messages may still be in the socket.
      while (!done() && lcm.handleTimeout(200) > 0) {
      }
      return done();
    }
    lcm.handleTimeout(50);
  }
  return false;
}

std::vector<pid_t> children_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/task/" + std::to_string(pid) + "/children");
  std::vector<pid_t> out;
  for (pid_t c; in >> c;) out.push_back(c);
  return out;
}

ChildProcess trainer(const std::vector<std::string>& args, const std::string& log) {
  std::vector<std::string> argv{kBin + "rise-trainer"};
  argv.insert(argv.end(), args.begin(), args.end());
  return ChildProcess(argv, log);
}

std::string training_file(const std::string& dir, const std::string& name,
                          const std::vector<std::pair<std::string, std::string>>& nodes) {
  std::string text = "training: " + name + "\nnodes:\n";
  for (const auto& [node, task] : nodes) text += "  - {name: " + node + ", task: " + src(task) + "}\n";
  text += "transitions:\n  - {from: START, to: " + nodes.front().first + "}\n";
  for (std::size_t i = 0; i + 1 < nodes.size(); ++i)
    text += "  - {from: " + nodes[i].first + ", to: " + nodes[i + 1].first + "}\n";
  text += "  - {from: " + nodes.back().first + ", to: END}\n";
  return rise::test::write_file(dir, name + ".yaml", text);
}

int count_entries(const std::vector<JournalEntry>& j, const std::string& type, const std::string& node) {
  int n = 0;
  for (const auto& e : j) n += e.type == type && e.node == node ? 1 : 0;
  return n;
}

// Largest step between consecutive trajectory points (m): another trainee's
// states mixed in would show as a jump across the building.
double largest_jump_m(const TaskResult& r) {
  double jump = 0;
  for (std::size_t i = 1; i < r.trajectory.size(); ++i)
    jump = std::max(jump, std::hypot(r.trajectory[i].x_m - r.trajectory[i - 1].x_m,
                                     r.trajectory[i].y_m - r.trajectory[i - 1].y_m));
  return jump;
}

}  // namespace

TEST_CASE("run-task scores a scripted drive beside a running rise-sim over LCM", "[training]") {
  const auto dir = rise::test::temp_dir("run-task");
  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  Heard heard;
  listen(lcm, "rt", heard);
  ChildProcess sim({kBin + "rise-sim", "--id", "rt", "--lcm", kLcm, "--robot", src("sim/robots/tracked_eod.yaml") + "@4.0,0.0,36.87",
                    "--world", src("sim/worlds/building.yaml")},
                   dir + "/sim.log");
  auto exec = trainer({"run-task", src("sim/training/examples/approach_object.yaml"), "--id", "rt", "--lcm", kLcm, "--out", dir,
                       "--scripted-console"},
                      dir + "/trainer.log");
  const bool finished = until(lcm, [&] {
    for (const auto& s : heard.statuses) if (s.state == "finished") return true;
    return false;
  }, {&exec});
  INFO(rise::test::read_file(dir + "/trainer.log"));
  REQUIRE(finished);
  CHECK(exec.wait_for(10000) == 0);
  sim.stop();
  const auto r = task_result_from_json(rise::test::read_file(dir + "/task_approach_object.json"));
  CHECK(r.success);
  CHECK(r.score == 20);
  CHECK(r.end_reason == "event object_touched");
  REQUIRE(heard.events.size() == 2);
  CHECK(heard.events[0].name == "near_object");
  CHECK(heard.events[1].name == "object_touched");
  CHECK(heard.events[1].score == 20);
  CHECK(heard.events[1].trainee_id == "rt");
  CHECK(heard.statuses.back().state == "finished");
  CHECK(heard.statuses.back().success);
  CHECK(std::filesystem::exists(dir + "/task_approach_object.html"));
}

TEST_CASE("a training resumes from its journal after kill -9 of the simulator and of the manager", "[training]") {
  const auto dir = rise::test::temp_dir("resume");
  const auto file = training_file(dir, "two_missions",
                                  {{"first", "sim/training/examples/approach_object.yaml"},
                                   {"second", "sim/training/examples/neutralize_object.yaml"}});
  const auto out = dir + "/out";
  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  Heard heard;
  listen(lcm, "kid", heard);
  const std::vector<std::string> args{"train", file, "--id", "kid", "--lcm", kLcm, "--out", out, "--scripted-console"};
  const auto second_running = [&] {
    for (const auto& s : heard.statuses)
      if (s.node == "second" && s.state == "running" && s.task_time_s > 0.5) return true;
    return false;
  };

  // 1. The simulator dies in the second task: the manager stops, the first result is kept.
  auto run1 = trainer(args, dir + "/run1.log");
  REQUIRE(until(lcm, second_running, {&run1}));
  const auto sims = children_of(run1.pid());
  REQUIRE(sims.size() == 1);
  ::kill(sims[0], SIGKILL);
  CHECK(run1.wait_for(20000) == 3);
  auto journal = read_journal(out + "/journal.jsonl");
  CHECK(count_entries(journal, "task_finished", "first") == 1);
  CHECK(count_entries(journal, "task_aborted", "second") == 1);
  const std::string first_report = rise::test::read_file(out + "/01_first_1.json");
  const auto first = task_result_from_json(first_report);
  CHECK(first.success);

  // 2. Resumed, the manager itself is killed in the second task (its simulator goes with it).
  heard.statuses.clear();
  auto run2 = trainer({"train", file, "--id", "kid", "--lcm", kLcm, "--out", out, "--scripted-console", "--resume"},
                      dir + "/run2.log");
  REQUIRE(until(lcm, second_running, {&run2}));
  for (const auto& s : heard.statuses) CHECK(s.node == "second");  // the first task is not run again
  run2.signal(SIGKILL);
  CHECK(run2.wait_for(10000) == 128 + SIGKILL);

  // 3. Resumed again, it finishes.
  auto run3 = trainer({"train", file, "--id", "kid", "--lcm", kLcm, "--out", out, "--scripted-console", "--resume"},
                      dir + "/run3.log");
  INFO(rise::test::read_file(dir + "/run3.log"));
  CHECK(run3.wait_for(60000) == 0);
  journal = read_journal(out + "/journal.jsonl");
  CHECK(count_entries(journal, "task_finished", "first") == 1);
  CHECK(count_entries(journal, "task_started", "second") == 3);
  CHECK(count_entries(journal, "task_finished", "second") == 1);
  CHECK(journal.back().type == "training_finished");
  CHECK(rise::test::read_file(out + "/01_first_1.json") == first_report);  // untouched
  const auto training = rise::test::read_file(out + "/training.json");
  CHECK_THAT(training, Catch::Matchers::Contains("\"finished\" : true"));
  CHECK_THAT(training, Catch::Matchers::Contains("\"total_score\" : " + std::to_string(first.score + 25)));
  const auto second = task_result_from_json(rise::test::read_file(out + "/02_second_1.json"));
  CHECK(second.success);
  CHECK(std::filesystem::exists(out + "/training.html"));
}

TEST_CASE("two trainees train at once on one LCM network without cross-talk, and the instructor lists both", "[training]") {
  const auto dir = rise::test::temp_dir("classroom");
  const auto a = training_file(dir, "a_training", {{"approach", "sim/training/examples/approach_object.yaml"}});
  const auto b = training_file(dir, "b_training", {{"neutralize", "sim/training/examples/neutralize_object.yaml"}});
  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  Heard ha, hb;
  listen(lcm, "ta", ha);
  listen(lcm, "tb", hb);
  auto instructor = trainer({"status", "--lcm", kLcm, "--trainees", "2", "--count", "1", "--every", "0.5"},
                            dir + "/status.log");
  auto ta = trainer({"train", a, "--id", "ta", "--lcm", kLcm, "--out", dir + "/a", "--scripted-console"}, dir + "/ta.log");
  auto tb = trainer({"train", b, "--id", "tb", "--lcm", kLcm, "--out", dir + "/b", "--scripted-console"}, dir + "/tb.log");
  until(lcm, [] { return false; }, {&ta, &tb}, 60);
  CHECK(ta.wait_for(1000) == 0);
  CHECK(tb.wait_for(1000) == 0);
  CHECK(instructor.wait_for(10000) == 0);
  const auto ra = task_result_from_json(rise::test::read_file(dir + "/a/01_approach_1.json"));
  const auto rb = task_result_from_json(rise::test::read_file(dir + "/b/01_neutralize_1.json"));
  CHECK(ra.success);
  CHECK(ra.score == 20);
  CHECK(rb.success);
  CHECK(rb.score == 25);
  CHECK(largest_jump_m(ra) < 0.2);
  CHECK(largest_jump_m(rb) < 0.2);
  CHECK(ra.trajectory.front().x_m == Approx(4.0).margin(0.05));
  CHECK(rb.trajectory.front().x_m == Approx(5.36).margin(0.05));
  for (const auto& e : ha.events) {
    CHECK(e.trainee_id == "ta");
    CHECK((e.name == "near_object" || e.name == "object_touched"));
  }
  for (const auto& e : hb.events) {
    CHECK(e.trainee_id == "tb");
    CHECK((e.name == "neutralized" || e.name == "gripper_near"));
  }
  CHECK(ha.events.size() == 2);
  CHECK(hb.events.size() == 2);
  const auto table = rise::test::read_file(dir + "/status.log");
  INFO(table);
  CHECK_THAT(table, Catch::Matchers::Contains("\nta "));
  CHECK_THAT(table, Catch::Matchers::Contains("\ntb "));
  CHECK_THAT(table, Catch::Matchers::Contains("a_training"));
  CHECK_THAT(table, Catch::Matchers::Contains("b_training"));
}

TEST_CASE("run-task ends the task as simulator lost when rise-sim goes silent, and still writes the report", "[training]") {
  const auto dir = rise::test::temp_dir("sim-lost");
  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  Heard heard;
  listen(lcm, "lost", heard);
  ChildProcess sim({kBin + "rise-sim", "--id", "lost", "--lcm", kLcm, "--robot", src("sim/robots/tracked_eod.yaml"),
                    "--world", src("sim/worlds/building.yaml")},
                   dir + "/sim.log");
  auto exec = trainer({"run-task", src("sim/training/examples/metro_transport.yaml"), "--id", "lost", "--lcm", kLcm,
                       "--out", dir, "--sim-timeout", "1"},
                      dir + "/trainer.log");
  REQUIRE(until(lcm, [&] {
    for (const auto& s : heard.statuses) if (s.state == "running" && s.task_time_s > 0.5) return true;
    return false;
  }, {&exec}));
  sim.signal(SIGKILL);
  const auto finished = [&] { return !heard.statuses.empty() && heard.statuses.back().state == "finished"; };
  CHECK(until(lcm, finished, {&exec}, 20));  // its last status goes out before it exits
  INFO(rise::test::read_file(dir + "/trainer.log"));
  CHECK(exec.wait_for(20000) == 0);
  const auto r = task_result_from_json(rise::test::read_file(dir + "/task_metro_transport.json"));
  CHECK(r.end_reason == "simulator lost");
  CHECK_FALSE(r.success);
  CHECK(r.time_s > 0);
  CHECK(heard.statuses.back().state == "finished");
  CHECK(heard.statuses.back().end_reason == "simulator lost");
}
