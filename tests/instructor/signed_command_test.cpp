// Signed instructor commands against the real programs over LCM multicast
// (udpm, ttl=0): rise-hild and rise-sim started as processes with an
// instructor key, fed good, unsigned, wrongly signed and replayed commands;
// a station without the key accepts none; rise-instructor's inject is
// confirmed by the daemon.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>

#include "msgs/channels.hpp"
#include "msgs/command_auth.hpp"
#include "msgs/failsafe.hpp"
#include "process/child_process.hpp"
#include "tests/process_support.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/TrainingControl.hpp"
#include "sim/training/report.hpp"

namespace fs = std::filesystem;

namespace {
const std::string kLcm = rise::msgs::kDefaultLcmUrl;

// The instructor's side of the network for one trainee.
class Station {
 public:
  explicit Station(std::string id) : id_(std::move(id)), lcm_(kLcm) {
    lcm_.subscribe(rise::msgs::panel_state_channel(id_), &Station::on_panel, this)->setQueueCapacity(1000);
    lcm_.subscribe(rise::msgs::robot_state_channel(id_), &Station::on_robot, this)->setQueueCapacity(1000);
    lcm_.subscribe(rise::msgs::sim_event_channel(id_), &Station::on_event, this)->setQueueCapacity(1000);
    lcm_.subscribe(rise::msgs::fault_command_channel(id_), &Station::on_command, this)->setQueueCapacity(1000);
  }
  bool good() { return lcm_.good(); }
  bool wait_until(const std::function<bool()>& done, int timeout_ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (!done()) {
      if (std::chrono::steady_clock::now() >= end) return false;
      lcm_.handleTimeout(10);
    }
    return true;
  }
  void send(const rise_msgs::FaultCommand& c) { lcm_.publish(rise::msgs::fault_command_channel(id_), &c); }
  void send(const rise_msgs::TrainingControl& c) { lcm_.publish(rise::msgs::training_control_channel(id_), &c); }

  // A PanelState with an active_faults entry starting with `prefix`, newer than now.
  bool panel_shows(const std::string& prefix, int timeout_ms = 10000) {
    panel_.reset();
    return wait_until([&] { return panel_ && has(panel_->active_faults, prefix); }, timeout_ms);
  }
  bool panel_clear_of(const std::string& prefix, int timeout_ms = 10000) {
    panel_.reset();
    return wait_until([&] { return panel_ && !has(panel_->active_faults, prefix); }, timeout_ms);
  }
  // The next SimEvent of `kind` whose detail contains `detail`.
  std::optional<rise_msgs::SimEvent> event(const std::string& kind, const std::string& detail, int timeout_ms = 10000) {
    std::optional<rise_msgs::SimEvent> found;
    wait_until([&] {
      for (const auto& e : events_)
        if (e.kind == kind && e.detail.find(detail) != std::string::npos) found = e;
      return found.has_value();
    }, timeout_ms);
    events_.clear();
    return found;
  }

  std::optional<rise_msgs::PanelState> panel_;
  std::optional<rise_msgs::RobotState> robot_;
  std::vector<rise_msgs::SimEvent> events_;
  int commands_seen_ = 0;  // FaultCommands on the trainee's channel, the station's own included

 private:
  static bool has(const std::vector<std::string>& v, const std::string& prefix) {
    for (const auto& s : v)
      if (s.rfind(prefix, 0) == 0) return true;
    return false;
  }
  void on_panel(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) { panel_ = *m; }
  void on_robot(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::RobotState* m) { robot_ = *m; }
  void on_event(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::SimEvent* m) { events_.push_back(*m); }
  void on_command(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::FaultCommand*) { ++commands_seen_; }
  std::string id_;
  lcm::LCM lcm_;
};

rise_msgs::FaultCommand command(const std::string& trainee, const std::string& action, const std::string& id,
                                const std::string& kind, const std::string& target, double duration_s = 0.0) {
  rise_msgs::FaultCommand c{};
  c.issuer = "test";
  c.trainee_id = trainee;
  c.action = action;
  c.fault_id = id;
  c.kind = kind;
  c.target = target;
  c.value = 0.5;
  c.duration_s = duration_s;
  c.seed = 1;
  c.signature_len = 0;
  return c;
}

rise_msgs::FaultCommand signed_with(rise_msgs::FaultCommand c, const rise::msgs::InstructorKey& key) {
  rise::msgs::sign(c, key);
  return c;
}

struct KeyDir {
  fs::path dir;
  std::string key_file;
  rise::msgs::InstructorKey key;
  explicit KeyDir(const std::string& name) {
    dir = fs::temp_directory_path() / (name + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    key_file = (dir / "instructor.key").string();
    key = rise::msgs::write_new_instructor_key(key_file);
  }
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

rise::msgs::InstructorKey other_key() {
  rise::msgs::InstructorKey k;
  k.bytes.assign(32, 0x5a);
  return k;
}
}  // namespace

TEST_CASE("rise-instructor inject goes again, signed afresh, until the daemon confirms it", "[instructor]") {
  // The first copy goes to nobody (rise-hild starts once it is out): lost
  // like a datagram dropped under load; a later copy is taken, not as a replay.
  const std::string id = "fr" + std::to_string(::getpid());
  KeyDir keys("rise-fault-resend-");
  INFO("logs in " << keys.dir);
  Station station(id);
  REQUIRE(station.good());
  const std::string out = (keys.dir / "cli.out").string();
  rise::process::ChildProcess cli({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "inject", "--lcm", kLcm,
                                   "--instructor-key", keys.key_file, "--trainee", id, "offset", "drive_x", "--value",
                                   "0.2", "--id", "late", "--confirm", "20"},
                                  out);
  // Its first copy is on the network before rise-hild listens.
  REQUIRE(station.wait_until([&] { return station.commands_seen_ >= 1; }, 20000));
  rise::process::ChildProcess hild({std::string(RISE_BINARY_DIR) + "/bin/rise-hild", "--lcm", kLcm, "--id", id,
                                    "--panel", std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml",
                                    "--source", "mem://" + id, "--instructor-key", keys.key_file},
                                   (keys.dir / "rise-hild.log").string());
  CHECK(cli.wait_for(30000) == 0);
  const std::string said = read_file(out);
  CHECK_THAT(said, Catch::Contains("sent again"));
  CHECK_THAT(said, Catch::Contains("inject late on " + id + ": confirmed"));
  CHECK(station.panel_shows("late: offset drive_x"));
  hild.stop();  // every copy it took is in its log
  CHECK_THAT(read_file((keys.dir / "rise-hild.log").string()), !Catch::Contains("replayed"));
}

TEST_CASE("rise-instructor scenario sends an inject again, signed afresh, until the daemon shows it", "[instructor]") {
  // The scenario's inject goes out before rise-hild listens: lost like a
  // datagram dropped under load; a later copy applies, not as a replay.
  const std::string id = "fq" + std::to_string(::getpid());
  KeyDir keys("rise-scenario-resend-");
  INFO("logs in " << keys.dir);
  Station station(id);
  REQUIRE(station.good());
  const std::string file = (keys.dir / "s.yaml").string();
  std::ofstream(file) << "scenario: s\nseed: 2\nfaults:\n"
                         "  - {id: sq, kind: stuck_at, target: drive_x, value: 0.3, at: 0.1, duration: 8.0}\n";
  const std::string out = (keys.dir / "scenario.out").string();
  rise::process::ChildProcess run({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "scenario", file, "--lcm",
                                   kLcm, "--instructor-key", keys.key_file, "--trainee", id},
                                  out);
  REQUIRE(rise::test::wait_for_text(out, "inject sq stuck_at", 20000));
  rise::process::ChildProcess hild({std::string(RISE_BINARY_DIR) + "/bin/rise-hild", "--lcm", kLcm, "--id", id,
                                    "--panel", std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml",
                                    "--source", "mem://" + id, "--instructor-key", keys.key_file},
                                   (keys.dir / "rise-hild.log").string());
  CHECK(station.panel_shows("sq: stuck_at drive_x"));
  // The scenario logs a copy after publishing it: the panel can show the
  // fault before the line is in the file.
  CHECK(rise::test::wait_for_text(out, "inject sq not shown yet, sent again", 5000));
  run.stop();
  hild.stop();  // every copy it took is in its log
  CHECK_THAT(read_file((keys.dir / "rise-hild.log").string()), !Catch::Contains("replayed"));
}

TEST_CASE("rise-hild applies a signed fault and rejects and reports unsigned, wrongly signed and replayed ones",
          "[instructor]") {
  const std::string id = "fh" + std::to_string(::getpid());
  KeyDir keys("rise-fault-hild-");
  INFO("logs in " << keys.dir);
  Station station(id);
  REQUIRE(station.good());
  const std::string log = (keys.dir / "rise-hild.log").string();
  rise::process::ChildProcess hild({std::string(RISE_BINARY_DIR) + "/bin/rise-hild", "--lcm", kLcm, "--id", id,
                                "--panel", std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml",
                                "--source", "mem://" + id, "--instructor-key", keys.key_file},
                               log);
  REQUIRE(station.wait_until([&] { return station.panel_.has_value(); }, 20000));

  const auto good = signed_with(command(id, "inject", "f1", "stuck_at", "drive_y"), keys.key);
  station.send(good);
  REQUIRE(station.panel_shows("f1: stuck_at drive_y"));

  SECTION("replayed") {
    station.send(good);
    CHECK(station.panel_shows("command_rejected: replayed from 'test'"));
  }
  SECTION("unsigned") {
    station.send(command(id, "clear", "f1", "", ""));
    CHECK(station.panel_shows("command_rejected: unsigned from 'test'"));
    CHECK(station.panel_shows("f1: stuck_at drive_y"));  // still in effect
  }
  SECTION("wrongly signed") {
    station.send(signed_with(command(id, "clear", "f1", "", ""), other_key()));
    CHECK(station.panel_shows("command_rejected: bad signature from 'test'"));
  }
  SECTION("signed for another trainee") {
    station.send(signed_with(command("someone-else", "clear", "f1", "", ""), keys.key));
    CHECK(station.panel_shows("command_rejected: meant for trainee 'someone-else'"));
  }
  SECTION("a signed clear clears it, a wire fault shows under its source") {
    station.send(signed_with(command(id, "clear", "f1", "", ""), keys.key));
    CHECK(station.panel_clear_of("f1:"));
    station.send(signed_with(command(id, "inject", "w1", "can_drop", "console", 0.5), keys.key));
    CHECK(station.panel_shows("w1: can_drop console"));
    CHECK(station.panel_clear_of("w1:"));  // its 0.5 s duration ends it
  }
  SECTION("rise-instructor inject is confirmed; without the key it sends nothing") {
    const std::string out = (keys.dir / "cli.out").string();
    rise::process::ChildProcess cli({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "inject", "--lcm", kLcm,
                                 "--instructor-key", keys.key_file, "--trainee", id, "offset", "drive_x", "--value",
                                 "0.2", "--id", "cli", "--confirm", "10"},
                                out);
    CHECK(cli.wait_for(20000) == 0);
    CHECK_THAT(read_file(out), Catch::Contains("inject cli on " + id + ": confirmed"));
    const std::string out2 = (keys.dir / "cli2.out").string();
    rise::process::ChildProcess nokey({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "clear", "--lcm", kLcm,
                                   "--instructor-key", (keys.dir / "missing.key").string(), "--trainee", id},
                                  out2);
    CHECK(nokey.wait_for(20000) == 2);
    CHECK_THAT(read_file(out2), Catch::Contains("missing.key"));
  }
  SECTION("rise-instructor lists the trainee and runs a scenario against it") {
    const std::string out = (keys.dir / "list.out").string();
    rise::process::ChildProcess list({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "list", "--lcm", kLcm,
                                  "--wait", "1.5"},
                                 out);
    CHECK(list.wait_for(20000) == 0);
    CHECK_THAT(read_file(out), Catch::Contains(id) && Catch::Contains("f1: stuck_at drive_y"));
    const std::string file = (keys.dir / "s.yaml").string();
    std::ofstream(file) << "scenario: s\nseed: 2\nfaults:\n"
                           "  - {id: sc, kind: stuck_at, target: drive_x, value: 0.3, at: 0.2, duration: 1.0}\n";
    const std::string out2 = (keys.dir / "scenario.out").string();
    rise::process::ChildProcess run({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "scenario", file, "--lcm",
                                 kLcm, "--instructor-key", keys.key_file, "--trainee", id},
                                out2);
    CHECK(station.panel_shows("sc: stuck_at drive_x"));
    CHECK(run.wait_for(20000) == 0);
    CHECK_THAT(read_file(out2), Catch::Contains("scenario s on " + id + ": 1 commands"));
    CHECK(station.panel_clear_of("sc:"));
  }
  hild.stop();
  CHECK_THAT(read_file(log), Catch::Contains("fault 'f1' from 'test': stuck_at drive_y"));
}

TEST_CASE("rise-instructor report prints the newest task report of a trainee", "[instructor]") {
  KeyDir keys("rise-fault-report-");
  const fs::path dir = keys.dir / "reports" / "t9";
  fs::create_directories(dir);
  rise::sim::training::TaskResult r;
  r.task = "approach_object";
  r.score = 17;
  r.success = true;
  r.finished = true;
  r.end_reason = "event object_touched";
  rise::sim::training::write_file_atomically((dir / "01_approach_1.json").string(), rise::sim::training::task_result_json(r));
  const std::string out = (keys.dir / "report.out").string();
  rise::process::ChildProcess report({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "report", "--trainee", "t9",
                                  "--reports-dir", (keys.dir / "reports").string()},
                                 out);
  CHECK(report.wait_for(20000) == 0);
  const std::string text = read_file(out);
  CHECK_THAT(text, Catch::Contains("01_approach_1.json"));
  CHECK_THAT(text, Catch::Contains("\"approach_object\""));
  CHECK_THAT(text, Catch::Contains("score        17"));
  const std::string out2 = (keys.dir / "report2.out").string();
  fs::create_directories(keys.dir / "empty");  // a folder without a report: "no" (1); no folder: bad input (2)
  rise::process::ChildProcess none({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "report", "--trainee", "t8",
                                "--reports-dir", (keys.dir / "empty").string()},
                               out2);
  CHECK(none.wait_for(20000) == 1);
  CHECK_THAT(read_file(out2), Catch::Contains("no report"));
}

TEST_CASE("a station without the instructor key rejects every fault command", "[instructor]") {
  const std::string id = "fn" + std::to_string(::getpid());
  KeyDir keys("rise-fault-nokey-");
  Station station(id);
  REQUIRE(station.good());
  const std::string log = (keys.dir / "rise-hild.log").string();
  rise::process::ChildProcess hild({std::string(RISE_BINARY_DIR) + "/bin/rise-hild", "--lcm", kLcm, "--id", id,
                                "--source", "mem://" + id},
                               log);
  REQUIRE(station.wait_until([&] { return station.panel_.has_value(); }, 20000));
  station.send(signed_with(command(id, "inject", "f1", "disconnect", "deadman"), keys.key));
  CHECK(station.panel_shows("command_rejected: no instructor key on this station"));
  hild.stop();
  CHECK_THAT(read_file(log), Catch::Contains("rejected command on rise/" + id + "/fault_command"));
}

TEST_CASE("rise-sim applies a signed motor failure until its end and rejects forged and replayed commands",
          "[instructor]") {
  const std::string id = "fs" + std::to_string(::getpid());
  KeyDir keys("rise-fault-sim-");
  INFO("logs in " << keys.dir);
  Station station(id);
  REQUIRE(station.good());
  const std::string log = (keys.dir / "rise-sim.log").string();
  rise::process::ChildProcess sim({std::string(RISE_BINARY_DIR) + "/bin/rise-sim", "--lcm", kLcm, "--id", id, "--robot",
                               std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml", "--instructor-key",
                               keys.key_file},
                              log);
  REQUIRE(station.wait_until([&] { return station.robot_.has_value(); }, 20000));

  const auto good = signed_with(command(id, "inject", "m1", "motor_failure", "left", 0.5), keys.key);
  station.send(good);
  const auto injected = station.event("fault_injected", "motor_failure left");
  REQUIRE(injected);
  CHECK(injected->b == "m1");
  station.robot_.reset();
  CHECK(station.wait_until([&] {
    return station.robot_ && station.robot_->num_faults == 1 && station.robot_->active_faults[0] == "m1: motor_failure left";
  }, 5000));
  CHECK(station.event("fault_cleared", "ended"));  // after its 0.5 s of sim time

  station.send(good);
  CHECK(station.event("command_rejected", "replayed"));
  station.send(command(id, "inject", "m2", "motor_failure", "right"));
  CHECK(station.event("command_rejected", "unsigned"));
  station.send(signed_with(command(id, "inject", "m3", "motor_failure", "right"), other_key()));
  CHECK(station.event("command_rejected", "bad signature"));
  station.send(signed_with(command(id, "inject", "m4", "motor_failure", "middle"), keys.key));
  const auto refused = station.event("fault_refused", "not left or right");
  CHECK(refused);
  // A daemon kind on the same channel is rise-hild's: rise-sim neither applies nor refuses it.
  station.send(signed_with(command(id, "inject", "d1", "stuck_at", "drive_y"), keys.key));
  station.send(signed_with(command(id, "inject", "m5", "motor_weakness", "right", 0.2), keys.key));
  REQUIRE(station.wait_until([&] {
    for (const auto& e : station.events_)
      if (e.kind == "fault_injected" && e.b == "m5") return true;
    return false;
  }, 10000));
  for (const auto& e : station.events_) CHECK(e.b != "d1");
  station.events_.clear();

  rise_msgs::TrainingControl restart{};
  restart.issuer = "test";
  restart.trainee_id = id;
  restart.command = "restart";
  restart.signature_len = 0;
  station.send(restart);
  CHECK(station.event("command_rejected", "unsigned"));
  rise::msgs::sign(restart, keys.key);
  station.send(restart);
  CHECK(station.event("training_restarted", "task"));
  const std::string out = (keys.dir / "task.out").string();
  rise::process::ChildProcess stop({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "task", "stop", "--lcm", kLcm,
                                "--instructor-key", keys.key_file, "--trainee", id, "--confirm", "10"},
                               out);
  CHECK(stop.wait_for(20000) == 0);
  CHECK_THAT(read_file(out), Catch::Contains("task stop on " + id + ": training_stopped"));
  sim.stop();
  CHECK_THAT(read_file(log), Catch::Contains("rejected command on rise/" + id + "/fault_command"));
}

TEST_CASE("a signed CAN drop over LCM makes the live daemon fail safe on the stale console and recover on the clear",
          "[instructor]") {
  const std::string id = "fw" + std::to_string(::getpid());
  KeyDir keys("rise-fault-wire-");
  INFO("logs in " << keys.dir);
  const std::string script = (keys.dir / "hold.txt").string();
  std::ofstream(script) << "0.0 mode drive\n0.0 speed fast\n0.1 deadman pressed\n0.2 drive_y 0.5\n";
  const std::string bus = "127.0.0.1:" + std::to_string(rise::test::free_tcp_port()) + "/can0";
  Station station(id);
  REQUIRE(station.good());
  rise::process::ChildProcess hild({std::string(RISE_BINARY_DIR) + "/bin/rise-hild", "--lcm", kLcm, "--id", id, "--source",
                                "socketcand://" + bus, "--instructor-key", keys.key_file},
                               (keys.dir / "rise-hild.log").string());
  rise::process::ChildProcess panel({std::string(RISE_BINARY_DIR) + "/bin/rise-panel", "emulate", "--can",
                                 "socketcand+listen://" + bus, "--script", script, "--hold", "--start-on-feedback"},
                                (keys.dir / "rise-panel.log").string());
  const auto healthy = [&] { return station.panel_ && !station.panel_->failsafe && station.panel_->deadman; };
  REQUIRE(station.wait_until(healthy, 20000));

  station.send(signed_with(command(id, "inject", "cut", "can_drop", "console"), keys.key));
  station.panel_.reset();
  REQUIRE(station.wait_until([&] {
    return station.panel_ && station.panel_->failsafe && rise::msgs::has(station.panel_->failsafe_causes, rise::msgs::FailsafeCause::SourceStale);
  }, 10000));
  CHECK(station.panel_shows("cut: can_drop console"));

  station.send(signed_with(command(id, "inject", "flip", "can_corrupt", "console"), keys.key));
  station.send(signed_with(command(id, "clear", "cut", "", ""), keys.key));
  station.panel_.reset();
  REQUIRE(station.wait_until([&] {
    return station.panel_ && station.panel_->num_sources == 1 && station.panel_->sources[0].crc_errors > 10;
  }, 10000));
  CHECK(station.panel_->failsafe);
  station.send(signed_with(command(id, "clear", "", "", ""), keys.key));
  station.panel_.reset();
  CHECK(station.wait_until(healthy, 10000));
  CHECK(station.panel_->active_faults.empty());
  panel.stop();
  hild.stop();
}
