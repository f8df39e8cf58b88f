// rise-sim as a separate process, paused, stepped and reset over real LCM
// multicast (udpm, ttl=0) with SimControl on rise/<id>/sim_control.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>

#include "msgs/channels.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimControl.hpp"
#include "rise_msgs/SimEvent.hpp"

namespace {
const std::string kLcm = rise::msgs::kDefaultLcmUrl;

/// The test's side of the LCM network: what rise-sim publishes, in arrival order.
class SimPeer {
 public:
  explicit SimPeer(const std::string& id) : lcm_(kLcm), id_(id) {
    lcm_.subscribe(rise::msgs::robot_state_channel(id), &SimPeer::on_state, this)->setQueueCapacity(1000);
    lcm_.subscribe(rise::msgs::sim_event_channel(id), &SimPeer::on_event, this)->setQueueCapacity(1000);
  }
  bool good() { return lcm_.good(); }

  /// Handles messages until `done` holds or timeout_ms passes; true if it held.
  bool wait_until(const std::function<bool()>& done, int timeout_ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (!done()) {
      if (std::chrono::steady_clock::now() >= end) return false;
      lcm_.handleTimeout(10);
    }
    return true;
  }

  /// Waits for the answer `kind` to command `seq`, then returns the next RobotState.
  std::optional<rise_msgs::RobotState> state_after_answer(const std::string& kind, int64_t seq) {
    answered_ = false;
    want_kind_ = kind;
    want_detail_ = "seq " + std::to_string(seq);
    if (!wait_until([&] { return answered_; }, 10000)) return std::nullopt;
    states_.clear();
    if (!wait_until([&] { return !states_.empty(); }, 5000)) return std::nullopt;
    return states_.front();
  }

  void send(const std::string& command, int64_t seq, int32_t steps = 0) {
    rise_msgs::SimControl c;
    c.utime = 0;
    c.issuer = "sim_control_test";
    c.seq = seq;
    c.command = command;
    c.steps = steps;
    lcm_.publish(rise::msgs::sim_control_channel(id_), &c);
  }

  /// Dead-man held, mode = drive, speed = fast, full forward.
  void drive_forward() {
    rise_msgs::PanelState p;
    p.utime = 0;
    p.panel_id = "test";
    p.trainee_id = id_;
    p.seq = 1;
    p.failsafe = false;
    p.deadman = true;
    p.axes = {{"drive_y", 1.0f}, {"drive_x", 0.0f}};
    p.num_axes = 2;
    p.buttons = {{"estop", false}};
    p.num_buttons = 1;
    p.switches = {{"mode", 0, "drive"}, {"speed", 2, "fast"}};
    p.num_switches = 2;
    p.num_sources = 0;
    p.num_faults = 0;
    lcm_.publish(rise::msgs::panel_state_channel(id_), &p);
  }

  std::vector<rise_msgs::RobotState> states_;
  std::vector<std::string> answer_details_;

 private:
  void on_state(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::RobotState* m) {
    states_.push_back(*m);
  }
  void on_event(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::SimEvent* m) {
    if (m->kind == want_kind_ && m->detail.rfind(want_detail_, 0) == 0) {
      answered_ = true;
      answer_details_.push_back(m->kind + " " + m->detail);
    }
  }

  lcm::LCM lcm_;
  std::string id_;
  std::string want_kind_;
  std::string want_detail_;
  bool answered_ = false;
};

double yaw_rad(const rise_msgs::RobotState& s) {
  const double* q = s.orientation_wxyz;
  return std::atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3]));
}
}  // namespace

TEST_CASE("rise-sim paused over LCM freezes sim time, steps exactly N ms and resets to the start pose", "[sim]") {
  const std::string id = "simctl" + std::to_string(::getpid());
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-simctl-" + id);
  std::filesystem::create_directories(dir);
  INFO("rise-sim log in " << dir);
  SimPeer peer(id);
  REQUIRE(peer.good());
  rise::process::ChildProcess sim({std::string(RISE_BINARY_DIR) + "/bin/rise-sim", "--id", id, "--lcm", kLcm, "--robot",
                               std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml"},
                              dir + "/rise-sim.log");
  // Ready: RobotState flows.
  REQUIRE(peer.wait_until([&] { return !peer.states_.empty(); }, 20000));
  const auto start = peer.states_.front();

  // Pause: states keep coming, all at one sim time.
  peer.send("pause", 1);
  const auto paused = peer.state_after_answer("sim_paused", 1);
  REQUIRE(paused);
  const double t_paused = paused->sim_time_s;
  REQUIRE(peer.wait_until([&] { return peer.states_.size() >= 10; }, 5000));  // 10 states: ~200 ms of wall time
  for (const auto& s : peer.states_) CHECK(s.sim_time_s == t_paused);

  // Step N while paused, with the robot driving: exactly N ms later, and it moved.
  peer.drive_forward();
  peer.send("step", 2, 1000);
  const auto stepped = peer.state_after_answer("sim_stepped", 2);
  REQUIRE(stepped);
  CHECK(stepped->sim_time_s == Approx(t_paused + 1.0).margin(1e-9));
  CHECK(stepped->position_m[0] > start.position_m[0] + 0.3);
  peer.send("step", 3, 250);
  const auto stepped2 = peer.state_after_answer("sim_stepped", 3);
  REQUIRE(stepped2);
  CHECK(stepped2->sim_time_s == Approx(t_paused + 1.25).margin(1e-9));
  REQUIRE(peer.wait_until([&] { return peer.states_.size() >= 5; }, 5000));
  for (const auto& s : peer.states_) CHECK(s.sim_time_s == stepped2->sim_time_s);  // still paused

  // Reset: time 0, the start pose, still paused.
  peer.send("reset", 4);
  const auto reset = peer.state_after_answer("sim_reset", 4);
  REQUIRE(reset);
  CHECK(reset->sim_time_s == 0.0);
  CHECK(reset->position_m[0] == Approx(0.0).margin(1e-9));  // the yard's robot_start
  CHECK(reset->position_m[1] == Approx(0.0).margin(1e-9));
  CHECK(reset->position_m[2] == Approx(start.position_m[2]).margin(0.01));  // settled 20 ms in vs. as built
  CHECK(yaw_rad(*reset) == Approx(0.0).margin(1e-9));
  CHECK(reset->damage == 0.0f);
  REQUIRE(peer.wait_until([&] { return peer.states_.size() >= 5; }, 5000));
  for (const auto& s : peer.states_) CHECK(s.sim_time_s == 0.0);

  // Resume: time runs again.
  peer.send("resume", 5);
  REQUIRE(peer.state_after_answer("sim_resumed", 5));
  CHECK(peer.wait_until([&] { return !peer.states_.empty() && peer.states_.back().sim_time_s > 0.2; }, 5000));

  // An unknown command is answered, not obeyed.
  peer.send("rewind", 6);
  REQUIRE(peer.state_after_answer("sim_control_refused", 6));
  CHECK(peer.answer_details_.back() ==
        "sim_control_refused seq 6: command 'rewind' with steps 0: expected pause, resume, step (steps 1..3600000) "
        "or reset");

  CHECK(sim.stop() == 0);
  std::filesystem::remove_all(dir);
}
