// rise-sim with two robots as a separate process over real LCM multicast
// (udpm, ttl=0): each robot on its own channels, moving only under its own
// PanelState, each with its own SoundCue stream on rise/<id>/sound.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>

#include "msgs/channels.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimControl.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/SoundCue.hpp"

namespace {
const std::string kLcm = rise::msgs::kDefaultLcmUrl;

/// The test's side of the LCM network for several robots: what rise-sim
/// publishes on each robot's channels, in arrival order.
class WorldPeer {
 public:
  explicit WorldPeer(const std::vector<std::string>& ids) : lcm_(kLcm) {
    for (const auto& id : ids) {
      lcm_.subscribe(rise::msgs::robot_state_channel(id), &WorldPeer::on_state, this)->setQueueCapacity(1000);
      lcm_.subscribe(rise::msgs::sim_event_channel(id), &WorldPeer::on_event, this)->setQueueCapacity(1000);
      lcm_.subscribe(rise::msgs::sound_channel(id), &WorldPeer::on_sound, this)->setQueueCapacity(10000);
    }
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

  /// Sends `command` on robot `id`'s control channel and waits for the answer
  /// on its sim_event, then for the next RobotState of every robot; false on a timeout.
  bool command(const std::string& id, const std::string& command, int64_t seq, int32_t steps = 0) {
    rise_msgs::SimControl c;
    c.utime = 0;
    c.issuer = "rise_sim_test";
    c.seq = seq;
    c.command = command;
    c.steps = steps;
    answers_.clear();
    lcm_.publish(rise::msgs::sim_control_channel(id), &c);
    const std::string want = "seq " + std::to_string(seq);
    if (!wait_until([&] { return answers_.count(id) && answers_[id].rfind(want, 0) == 0; }, 20000)) return false;
    states_.clear();
    return wait_until([&] { return states_.size() >= ids_seen_; }, 5000);
  }

  /// Dead-man held (or released), mode = drive, speed = fast, full forward, the horn button.
  void panel(const std::string& id, bool deadman, bool horn) {
    rise_msgs::PanelState p;
    p.utime = 0;
    p.panel_id = "test";
    p.trainee_id = id;
    p.seq = 1;
    p.failsafe = false;
    p.deadman = deadman;
    p.axes = {{"drive_y", 1.0f}, {"drive_x", 0.0f}};
    p.num_axes = 2;
    p.buttons = {{"estop", false}, {"horn", horn}};
    p.num_buttons = 2;
    p.switches = {{"mode", 0, "drive"}, {"speed", 2, "fast"}};
    p.num_switches = 2;
    p.num_sources = 0;
    p.num_faults = 0;
    lcm_.publish(rise::msgs::panel_state_channel(id), &p);
  }

  std::map<std::string, rise_msgs::RobotState> states_;  // newest per channel id
  std::map<std::string, std::vector<rise_msgs::SoundCue>> sounds_;
  std::size_t ids_seen_ = 0;

 private:
  static std::string id_of(const std::string& channel) {
    const auto a = channel.find('/') + 1;
    return channel.substr(a, channel.find('/', a) - a);
  }
  void on_state(const lcm::ReceiveBuffer*, const std::string& channel, const rise_msgs::RobotState* m) {
    states_[id_of(channel)] = *m;
  }
  void on_event(const lcm::ReceiveBuffer*, const std::string& channel, const rise_msgs::SimEvent* m) {
    if (m->a == "rise_sim_test") answers_[id_of(channel)] = m->detail;
  }
  void on_sound(const lcm::ReceiveBuffer*, const std::string& channel, const rise_msgs::SoundCue* m) {
    sounds_[id_of(channel)].push_back(*m);
  }

  lcm::LCM lcm_;
  std::map<std::string, std::string> answers_;
};

double yaw_rad(const rise_msgs::RobotState& s) {
  const double* q = s.orientation_wxyz;
  return std::atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3]));
}

// The newest continuous cue `name` among `cues`.
const rise_msgs::SoundCue* latest(const std::vector<rise_msgs::SoundCue>& cues, const std::string& name) {
  for (auto it = cues.rbegin(); it != cues.rend(); ++it)
    if (it->name == name && it->continuous) return &*it;
  return nullptr;
}
}  // namespace

TEST_CASE("rise-sim with two robots publishes a RobotState and sound cues per robot, each moved by its own panel",
          "[sim]") {
  const std::string a = "ma" + std::to_string(::getpid());
  const std::string b = "mb" + std::to_string(::getpid());
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-sim2-" + a);
  std::filesystem::create_directories(dir);
  INFO("rise-sim log in " << dir);
  WorldPeer peer({a, b});
  REQUIRE(peer.good());
  const std::string robots = std::string(RISE_SOURCE_DIR) + "/sim/robots/";
  // A long panel timeout: the steps below run at once, however slow the machine.
  rise::process::ChildProcess sim({std::string(RISE_BINARY_DIR) + "/bin/rise-sim", "--lcm", kLcm, "--robot",
                               a + "=" + robots + "skid4.yaml", "--robot", b + "=" + robots + "tracked_eod.yaml@0,3,90",
                               "--panel-timeout-ms", "10000"},
                              dir + "/rise-sim.log");
  REQUIRE(peer.wait_until([&] { return peer.states_.count(a) && peer.states_.count(b); }, 20000));
  peer.ids_seen_ = 2;
  CHECK(peer.states_[a].robot_id == a);
  CHECK(peer.states_[b].robot_id == b);
  CHECK(peer.states_[b].position_m[1] == Approx(3.0).margin(0.01));
  CHECK(yaw_rad(peer.states_[b]) == Approx(M_PI / 2).margin(0.01));

  REQUIRE(peer.command(a, "pause", 1));
  const auto a0 = peer.states_[a], b0 = peer.states_[b];

  // Only a's panel drives; the step goes in on b's control channel: either controls the one world.
  peer.panel(a, true, false);
  peer.panel(b, false, false);
  peer.sounds_.clear();
  REQUIRE(peer.command(b, "step", 2, 1000));
  auto a1 = peer.states_[a], b1 = peer.states_[b];
  CHECK(a1.sim_time_s == Approx(a0.sim_time_s + 1.0).margin(1e-9));
  CHECK(a1.position_m[0] > a0.position_m[0] + 0.5);
  CHECK(std::hypot(b1.position_m[0] - b0.position_m[0], b1.position_m[1] - b0.position_m[1]) < 0.02);
  CHECK(a1.motors_enabled);
  CHECK_FALSE(b1.motors_enabled);
  // The engine sounds go out with the states: a's hum is up, b's silent.
  const auto* hum_a = latest(peer.sounds_[a], "wheel_motors");
  const auto* hum_b = latest(peer.sounds_[b], "tracks_motor");
  REQUIRE(hum_a != nullptr);
  REQUIRE(hum_b != nullptr);
  CHECK(hum_a->robot_id == a);
  CHECK(hum_a->gain > 0.5f);
  CHECK(hum_a->pitch > 1.3f);
  CHECK(hum_b->gain == 0.0f);
  CHECK(peer.sounds_[a].size() >= 50);  // 1 s at 50 Hz, one per continuous cue

  // Now only b drives, and a sounds its horn once.
  peer.panel(a, false, true);
  peer.panel(b, true, false);
  peer.sounds_.clear();
  REQUIRE(peer.command(a, "step", 3, 1000));
  const auto a2 = peer.states_[a], b2 = peer.states_[b];
  CHECK(b2.position_m[1] > b1.position_m[1] + 0.5);
  CHECK(std::fabs(b2.position_m[0] - b1.position_m[0]) < 0.1);
  CHECK(a2.position_m[0] < a1.position_m[0] + 0.4);  // braking only
  int horns_a = 0, horns_b = 0;
  for (const auto& c : peer.sounds_[a]) horns_a += c.name == "horn" && !c.continuous;
  for (const auto& c : peer.sounds_[b]) horns_b += c.name == "horn";
  CHECK(horns_a == 1);
  CHECK(horns_b == 0);
  REQUIRE(latest(peer.sounds_[b], "tracks_motor"));
  CHECK(latest(peer.sounds_[b], "tracks_motor")->gain > 0.5f);

  CHECK(sim.stop() == 0);
  std::filesystem::remove_all(dir);
}

namespace {
// RobotState's joint `name` (position, velocity), NaNs if absent.
std::pair<double, double> joint_of(const rise_msgs::RobotState& s, const std::string& name) {
  for (std::size_t i = 0; i < s.joint_names.size(); ++i)
    if (s.joint_names[i] == name) return {s.joint_positions[i], s.joint_velocities[i]};
  return {NAN, NAN};
}
}  // namespace

TEST_CASE("rise-sim drives the urdf_tree TurtleBot3 Burger's wheel joints as its robot file maps the panel",
          "[sim]") {
  const std::string id = "tb" + std::to_string(::getpid());
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-sim-tb-" + id);
  std::filesystem::create_directories(dir);
  INFO("rise-sim log in " << dir);
  WorldPeer peer({id});
  REQUIRE(peer.good());
  const std::string robots = std::string(RISE_SOURCE_DIR) + "/sim/robots/";
  rise::process::ChildProcess sim({std::string(RISE_BINARY_DIR) + "/bin/rise-sim", "--lcm", kLcm, "--robot",
                                   id + "=" + robots + "turtlebot3_burger.yaml", "--panel-timeout-ms", "10000"},
                                  dir + "/rise-sim.log");
  REQUIRE(peer.wait_until([&] { return peer.states_.count(id) > 0; }, 20000));
  peer.ids_seen_ = 1;
  REQUIRE(peer.command(id, "pause", 1));
  const auto s0 = peer.states_[id];
  REQUIRE(s0.num_joints == 2);  // the two wheels: the caster and the scanner are fixed
  CHECK(s0.joint_names[0] == "wheel_left_joint");

  peer.panel(id, true, false);  // full forward, dead-man held
  REQUIRE(peer.command(id, "step", 2, 2000));
  const auto s1 = peer.states_[id];
  CHECK(s1.motors_enabled);
  CHECK(s1.position_m[0] - s0.position_m[0] == Approx(0.4).margin(0.06));  // 0.22 m/s for 2 s, less the spin-up
  CHECK(joint_of(s1, "wheel_left_joint").second == Approx(6.67).margin(0.1));
  CHECK(joint_of(s1, "wheel_right_joint").second == Approx(6.67).margin(0.1));
  CHECK(joint_of(s1, "wheel_left_joint").first - joint_of(s0, "wheel_left_joint").first > 10.0);  // > 1.5 turns

  peer.panel(id, false, false);  // dead-man released: the wheel motors hold
  REQUIRE(peer.command(id, "step", 3, 1000));
  const auto s2 = peer.states_[id];
  CHECK_FALSE(s2.motors_enabled);
  CHECK(std::fabs(joint_of(s2, "wheel_left_joint").second) < 0.05);
  CHECK(s2.position_m[0] - s1.position_m[0] < 0.05);

  CHECK(sim.stop() == 0);
  std::filesystem::remove_all(dir);
}
