// The whole chain in separate processes: rise-panel (console firmware,
// socketcand server) → rise-hild → real LCM multicast → rise-sim, with
// lcm-logger recording beside them. Asserts the stop times the safety
// rules promise.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <csignal>
#include <unistd.h>

#include <filesystem>
#include <set>

#include "msgs/channels.hpp"
#include "panels/panel_definition.hpp"
#include "process/chain_monitor.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "sim/simulation.hpp"
#include "tests/integration/integration_support.hpp"

using rise::process::ChainView;
using rise::process::ChildProcess;
using rise::test::kBin;
using rise::test::kSource;

namespace {
const std::string kLcm = rise::msgs::kDefaultLcmUrl;

}  // namespace

TEST_CASE("the robot stops within two publish periods plus its own stop time after a dead-man release and "
          "after the console is killed",
          "[integration]") {
  const auto def = rise::panels::load_panel_definition(kSource + "/panels/definitions/rise_console.yaml");
  const auto robot = rise::sim::load_robot_description(kSource + "/sim/robots/skid4.yaml");
  const double publish_period_s = 1.0 / def.publish_hz;
  const double robot_state_period_s = 1.0 / 50.0;
  const std::string id = "itest" + std::to_string(::getpid());
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-chain-" + id);
  std::filesystem::create_directories(dir);
  const std::string bus = "127.0.0.1:" + std::to_string(rise::test::free_tcp_port()) + "/can0";

  rise::process::ChainMonitor monitor(kLcm, id);
  REQUIRE(monitor.good());

  const std::string log_file = dir + "/chain.lcmlog";
  ChildProcess logger({"/usr/bin/lcm-logger", "-q", "-f", "--lcm-url=" + kLcm, "-c", "rise/" + id + "/.*", log_file},
                      dir + "/lcm-logger.log");
  ChildProcess sim({kBin + "/rise-sim", "--id", id, "--lcm", kLcm}, dir + "/rise-sim.log");
  ChildProcess hild({kBin + "/rise-hild", "--can", "socketcand://" + bus, "--id", id, "--lcm", kLcm},
                    dir + "/rise-hild.log");
  ChildProcess panel({kBin + "/rise-panel", "emulate", "--can", "socketcand+listen://" + bus, "--script",
                      kSource + "/tests/integration/chain_script.txt", "--hold", "--start-on-feedback"},
                     dir + "/rise-panel.log");

  INFO("logs in " << dir);
  REQUIRE(monitor.wait_until([](const ChainView& v) { return v.have_robot && v.have_panel && !v.panel.failsafe; },
                             15000));

  // 1. Dead-man release at full speed.
  REQUIRE(monitor.wait_until([](const ChainView& v) { return v.deadman_stop.stopped; }, 15000));
  auto v = monitor.view();
  const double sim_stop_s = rise::sim::stop_time_s(robot, v.deadman_stop.speed_at_trigger_mps);
  const double deadman_bound_s = 2 * publish_period_s + sim_stop_s + robot_state_period_s;
  INFO("dead-man: " << v.deadman_stop.seconds() << " s from " << v.deadman_stop.speed_at_trigger_mps
                    << " m/s; sim stop time " << sim_stop_s << " s; bound " << deadman_bound_s << " s");
  CHECK(v.deadman_stop.speed_at_trigger_mps > 0.5);
  CHECK(v.deadman_stop.seconds() <= deadman_bound_s);

  // 2. Driving again, then the console process dies.
  REQUIRE(monitor.wait_until([](const ChainView& v) { return v.panel.deadman && v.speed_mps > 0.5; }, 15000));
  panel.signal(SIGKILL);
  REQUIRE(panel.wait_for(5000) == 128 + SIGKILL);
  REQUIRE(monitor.wait_until([](const ChainView& v) { return v.loss_stop.stopped; }, 10000));
  v = monitor.view();
  const double loss_sim_stop_s = rise::sim::stop_time_s(robot, v.loss_stop.speed_at_trigger_mps);
  const double loss_bound_s = 2 * publish_period_s + loss_sim_stop_s + robot_state_period_s;
  INFO("source loss (" << v.loss_reason << "): " << v.loss_stop.seconds() << " s; bound " << loss_bound_s << " s");
  CHECK(v.loss_reason.find("console") != std::string::npos);
  CHECK(v.loss_stop.seconds() <= loss_bound_s);
  CHECK(v.distance_m > 1.0);

  // Every process is still up, and stops cleanly on SIGTERM.
  CHECK(hild.stop() == 0);
  CHECK(sim.stop() == 0);
  logger.stop();

  // 3. lcm-logger, a third-party LCM peer, recorded both channels.
  lcm::LogFile log(log_file, "r");
  REQUIRE(log.good());
  int64_t panel_events = 0, robot_events = 0;
  bool decoded = true;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel == rise::msgs::panel_state_channel(id)) {
      rise_msgs::PanelState m;
      decoded = decoded && m.decode(e->data, 0, static_cast<int>(e->datalen)) > 0 && m.trainee_id == id;
      ++panel_events;
    } else if (e->channel == rise::msgs::robot_state_channel(id)) {
      rise_msgs::RobotState m;
      decoded = decoded && m.decode(e->data, 0, static_cast<int>(e->datalen)) > 0;
      ++robot_events;
    }
  }
  CHECK(decoded);
  CHECK(panel_events > 100);
  CHECK(robot_events > 50);
  std::filesystem::remove_all(dir);
}
