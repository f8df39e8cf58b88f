#include "msgs/channels.hpp"

namespace rise::msgs {
namespace {

constexpr std::string_view kPrefix = "rise/";

std::string station_channel(const std::string& trainee_id, std::string_view what) {
  std::string channel;
  channel.reserve(kPrefix.size() + trainee_id.size() + 1 + what.size());
  channel.append(kPrefix).append(trainee_id).append(1, '/').append(what);
  return channel;
}

}  // namespace

std::string panel_state_channel(const std::string& id) { return station_channel(id, "panel_state"); }
std::string panel_feedback_channel(const std::string& id) { return station_channel(id, "panel_feedback"); }
std::string robot_state_channel(const std::string& id) { return station_channel(id, "robot_state"); }
std::string sim_event_channel(const std::string& id) { return station_channel(id, "sim_event"); }
std::string sim_control_channel(const std::string& id) { return station_channel(id, "sim_control"); }
std::string sound_channel(const std::string& id) { return station_channel(id, "sound"); }
std::string task_event_channel(const std::string& id) { return station_channel(id, "task_event"); }
std::string task_status_channel(const std::string& id) { return station_channel(id, "task_status"); }
std::string fault_command_channel(const std::string& id) { return station_channel(id, "fault_command"); }
std::string training_control_channel(const std::string& id) { return station_channel(id, "training_control"); }
std::string clock_probe_channel(const std::string& id) { return station_channel(id, "clock_probe"); }
std::string clock_echo_channel(const std::string& id) { return station_channel(id, "clock_echo"); }

std::optional<StationChannel> parse_station_channel(const std::string& channel) {
  if (channel.rfind(kPrefix, 0) != 0) return std::nullopt;
  const std::size_t begin = kPrefix.size(), slash = channel.find('/', begin);
  if (slash == std::string::npos || slash == begin) return std::nullopt;
  std::string what = channel.substr(slash + 1);
  if (what.empty() || what.find('/') != std::string::npos) return std::nullopt;
  return StationChannel{channel.substr(begin, slash - begin), std::move(what)};
}

}  // namespace rise::msgs
