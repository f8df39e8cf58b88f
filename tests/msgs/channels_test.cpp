#include <catch2/catch.hpp>

#include <string>

#include "msgs/channels.hpp"

using rise::msgs::parse_station_channel;

TEST_CASE("every station channel is rise/<id>/<what> and reads back as its trainee and kind", "[msgs]") {
  using Channel = std::string (*)(const std::string&);
  const auto [channel, what] = GENERATE(table<Channel, std::string>({
      {rise::msgs::panel_state_channel, "panel_state"},
      {rise::msgs::panel_feedback_channel, "panel_feedback"},
      {rise::msgs::robot_state_channel, "robot_state"},
      {rise::msgs::sim_event_channel, "sim_event"},
      {rise::msgs::sim_control_channel, "sim_control"},
      {rise::msgs::sound_channel, "sound"},
      {rise::msgs::task_event_channel, "task_event"},
      {rise::msgs::task_status_channel, "task_status"},
      {rise::msgs::fault_command_channel, "fault_command"},
      {rise::msgs::training_control_channel, "training_control"},
      {rise::msgs::clock_probe_channel, "clock_probe"},
      {rise::msgs::clock_echo_channel, "clock_echo"},
  }));
  CHECK(channel("t1") == "rise/t1/" + what);
  const auto parsed = parse_station_channel(channel("lab-3"));
  REQUIRE(parsed);
  CHECK(parsed->trainee_id == "lab-3");
  CHECK(parsed->what == what);
}

TEST_CASE("a name that is not a station channel reads as none", "[msgs]") {
  const std::string name = GENERATE("robot_state", "rise/", "rise//robot_state", "rise/t1", "rise/t1/",
                                    "rise/t1/a/b", "other/t1/robot_state", "LCM_SELF_TEST");
  INFO(name);
  CHECK_FALSE(parse_station_channel(name));
}

TEST_CASE("the default LCM URL is LCM's own multicast group, kept on this machine", "[msgs]") {
  CHECK(std::string(rise::msgs::kDefaultLcmUrl) == "udpm://239.255.76.67:7667?ttl=0");
}
