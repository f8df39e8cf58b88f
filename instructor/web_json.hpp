#pragma once

// What the web console sends its pages, as JSON: the world and the robot the
// map and the 3D view draw, the console definition the virtual panel copies,
// the fault buttons, and the classroom's LCM messages (PanelState,
// RobotState, TaskStatus, SimEvent, TaskEvent, SoundCue, PanelFeedback) as the SSE stream and
// /api/trainees carry them. Pure: no I/O, no clock but the publisher's age.

#include <json/json.h>

#include <cstdint>
#include <string>
#include <vector>

#include "instructor/fault_presets.hpp"
#include "instructor/trainee_links.hpp"
#include "rise_msgs/PanelFeedback.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/Publisher.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/SoundCue.hpp"
#include "rise_msgs/TaskEvent.hpp"
#include "rise_msgs/TaskStatus.hpp"

namespace rise::panels {
struct PanelDefinition;
}
namespace rise::sim {
struct RobotDescription;
struct WorldDescription;
}  // namespace rise::sim

namespace rise::instructor {

/// `v` on one line (no indentation), as the API replies and SSE pushes carry it.
std::string json_text(const Json::Value& v);

/// The static scene as boxes the pages draw (world frame, z up), plus the
/// regions and the movable objects' start.
Json::Value world_json(const sim::WorldDescription& w);
/// What the 3D view draws of the robot: its chassis box and its camera
/// mounts (base frame, x forward, z up; rpy in radians); a urdf_tree robot's
/// `links` (name, rgba, visuals: type, size, origin {xyz, wxyz}, a mesh's
/// flat `vertices` and `triangles`) and `joints` (name, type, parent and
/// child link index, origin, axis).
Json::Value robot_json(const sim::RobotDescription& r);
/// The controls the virtual panel page draws, with the panel's publish rate
/// and the timeout after which it fails safe.
Json::Value panel_definition_json(const panels::PanelDefinition& panel, uint32_t timeout_ms);
/// The fault buttons the console shows, and whether they work (`is_signed`:
/// the server holds the instructor key).
Json::Value fault_buttons_json(const std::vector<FaultPreset>& presets, bool is_signed);

/// A message's publisher, with msgs::describe's text (its age now).
Json::Value publisher_json(const rise_msgs::Publisher& p);
Json::Value panel_json(const rise_msgs::PanelState& m);
/// Adds the yaw (rad, from the orientation quaternion) the map draws.
Json::Value robot_json(const rise_msgs::RobotState& m);
Json::Value task_status_json(const rise_msgs::TaskStatus& m);
Json::Value sim_event_json(const rise_msgs::SimEvent& m);
Json::Value task_event_json(const rise_msgs::TaskEvent& m);
/// What the trainee page's WebAudio plays (msgs/lcmtypes/SoundCue.lcm).
Json::Value sound_cue_json(const rise_msgs::SoundCue& m);
/// A trainee's link (instructor/trainee_links.hpp) in ms: state, heard_ago_ms,
/// arrival_age_ms, and clock_offset_ms / clock_delay_ms / clock_host once measured.
Json::Value link_json(const TraineeLink& l);
/// The console's LEDs and displays by name ({"leds": {NAME: on}, "displays":
/// {NAME: value}}), the buzzer ("off", "on", "beep") and the rumble.
Json::Value panel_feedback_json(const rise_msgs::PanelFeedback& m);

}  // namespace rise::instructor
