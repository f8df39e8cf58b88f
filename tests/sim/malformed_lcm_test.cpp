// rise-sim as a separate process over real LCM multicast, fed packets on its
// own channels that are not messages: a string length of 0 (lcm-gen's
// decode() throws std::length_error on it, and LCM's typed subscriptions let
// it through lcm_handle(): one such packet aborted rise-sim before
// msgs/lcm_decode.hpp), a truncated message and another type's bytes. It must
// drop them, count them, and go on answering.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "msgs/channels.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimControl.hpp"
#include "rise_msgs/TrainingControl.hpp"

namespace {

const std::string kLcm = "udpm://239.255.76.67:7692?ttl=0";

// A message's bytes with its first string's length (after the 8-byte type
// hash and `skip` bytes of fields before it) set to 0.
template <class Message>
std::vector<uint8_t> zero_length_string(const Message& m, int skip) {
  std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  for (int i = 0; i < 4; ++i) bytes[static_cast<size_t>(8 + skip + i)] = 0;
  return bytes;
}

struct Latest {
  int states = 0;
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::RobotState*) { ++states; }
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("rise-sim drops LCM packets that are not messages, counts them and keeps running", "[sim]") {
  const std::string id = "bad" + std::to_string(::getpid());
  const std::string log = std::filesystem::temp_directory_path() / ("rise-sim-malformed-" + id + ".log");
  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  Latest latest;
  lcm.subscribe(rise::msgs::robot_state_channel(id), &Latest::on, &latest);
  rise::process::ChildProcess sim({std::string(RISE_BINARY_DIR) + "/bin/rise-sim", "--id", id, "--lcm", kLcm}, log);
  const auto handle_for = [&](int ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (std::chrono::steady_clock::now() < end) lcm.handleTimeout(10);
  };
  const auto wait_states = [&](int n, int ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    latest.states = 0;
    while (latest.states < n && std::chrono::steady_clock::now() < end) lcm.handleTimeout(10);
    return latest.states >= n;
  };
  REQUIRE(wait_states(1, 20000));

  rise_msgs::TrainingControl training{};
  training.issuer = "x", training.trainee_id = id, training.command = "start", training.task = "t";
  rise_msgs::FaultCommand fault{};
  fault.issuer = "x", fault.trainee_id = id, fault.action = "inject", fault.kind = "motor_failure";
  rise_msgs::SimControl control{};
  control.issuer = "x", control.command = "pause";
  rise_msgs::PanelState panel{};
  panel.panel_id = "p", panel.trainee_id = id;
  const std::vector<uint8_t> panel_bytes = zero_length_string(panel, 8);
  const std::vector<std::pair<std::string, std::vector<uint8_t>>> packets = {
      {rise::msgs::training_control_channel(id), zero_length_string(training, 8)},  // issuer, after utime
      {rise::msgs::fault_command_channel(id), zero_length_string(fault, 8)},
      {rise::msgs::sim_control_channel(id), zero_length_string(control, 8)},
      {rise::msgs::panel_state_channel(id), panel_bytes},  // panel_id, after utime
      {rise::msgs::panel_state_channel(id), std::vector<uint8_t>(panel_bytes.begin(), panel_bytes.begin() + 11)},
      {rise::msgs::sim_control_channel(id), panel_bytes},  // another type's hash
  };
  for (const auto& [channel, bytes] : packets) {
    REQUIRE(lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())) == 0);
    handle_for(50);
  }
  // Still alive, still publishing.
  CHECK(sim.running());
  CHECK(wait_states(10, 5000));
  sim.stop();
  INFO(read_file(log));
  CHECK(read_file(log).find(std::to_string(packets.size()) + " malformed LCM messages dropped") != std::string::npos);
  std::filesystem::remove(log);
}
