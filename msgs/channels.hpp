#pragma once

// Where the processes meet: the LCM URL they share unless told otherwise, and
// the channels of one trainee station, rise/<trainee id>/<what> (DESIGN.md,
// "The contract between processes"). One function per channel, so that a
// publisher and its subscribers cannot spell a name two ways.

#include <optional>
#include <string>

namespace rise::msgs {

/// LCM's own default multicast group and port; ttl=0 keeps the traffic on
/// this machine until a classroom passes --lcm with a ttl of 1 (README
/// "A classroom on a LAN").
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

std::string panel_state_channel(const std::string& trainee_id);       ///< PanelState, rise-hild or a virtual panel
std::string panel_feedback_channel(const std::string& trainee_id);    ///< PanelFeedback, rise-sim → the console
std::string robot_state_channel(const std::string& trainee_id);       ///< RobotState, rise-sim
std::string sim_event_channel(const std::string& trainee_id);         ///< SimEvent, rise-sim
std::string sim_control_channel(const std::string& trainee_id);       ///< SimControl, the instructor → rise-sim
std::string sound_channel(const std::string& trainee_id);             ///< SoundCue, rise-sim → the trainee page
std::string task_event_channel(const std::string& trainee_id);        ///< TaskEvent, rise-trainer
std::string task_status_channel(const std::string& trainee_id);       ///< TaskStatus, rise-trainer
std::string fault_command_channel(const std::string& trainee_id);     ///< FaultCommand (signed), the instructor
std::string training_control_channel(const std::string& trainee_id);  ///< TrainingControl (signed), the instructor
std::string clock_probe_channel(const std::string& trainee_id);       ///< ClockProbe, the instructor → the station's processes
std::string clock_echo_channel(const std::string& trainee_id);        ///< ClockEcho, rise-hild and rise-sim → the instructor

/// A station channel taken apart: rise/<trainee>/<what>.
struct StationChannel {
  std::string trainee_id;
  std::string what;  ///< "panel_state", "robot_state", ...
};

/// The trainee and the kind of a station channel; nullopt for any other name
/// (no "rise/" prefix, an empty id, or more than one '/' after the id).
std::optional<StationChannel> parse_station_channel(const std::string& channel);

}  // namespace rise::msgs
