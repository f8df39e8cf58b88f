#include "instructor/web_json.hpp"

#include <cmath>

#include "msgs/clock.hpp"
#include "msgs/failsafe.hpp"
#include "msgs/publisher_session.hpp"
#include "panels/panel_definition.hpp"
#include "sim/robot_description.hpp"
#include "sim/world_description.hpp"

namespace rise::instructor {
namespace {

Json::Value xyz(const double* p) {
  Json::Value a(Json::arrayValue);
  for (int i = 0; i < 3; ++i) a.append(p[i]);
  return a;
}

Json::Value box_json(const sim::BoxObstacle& b, const std::string& kind) {
  Json::Value v;
  v["name"] = b.name;
  v["kind"] = kind;
  v["center"] = xyz(b.center_m.data());
  v["size"] = xyz(b.size_m.data());
  v["yaw"] = b.yaw_rad;
  return v;
}

}  // namespace

namespace {

// JSON has no infinity (jsoncpp writes 1e+9999, which the page's
// JSON.parse turns into Infinity and WebAudio refuses): a non-finite
// number anywhere in `v` becomes null, as jsoncpp writes NaN.
void finite_numbers(Json::Value& v) {
  if (v.isDouble() && !std::isfinite(v.asDouble())) v = Json::Value();
  else if (v.isArray() || v.isObject())
    for (auto& child : v) finite_numbers(child);
}

}  // namespace

std::string json_text(const Json::Value& v) {
  Json::StreamWriterBuilder b;
  b["indentation"] = "";
  Json::Value finite = v;
  finite_numbers(finite);
  return Json::writeString(b, finite);
}

Json::Value world_json(const sim::WorldDescription& w) {
  Json::Value out;
  out["name"] = w.name;
  out["file"] = w.file;
  Json::Value boxes(Json::arrayValue);
  for (const auto& b : w.boxes) boxes.append(box_json(b, "box"));
  for (const auto& p : w.props) boxes.append(box_json(p.box, p.kind.empty() ? "prop" : p.kind));
  for (const auto& wall : w.walls)
    for (const auto& b : sim::wall_boxes(wall)) boxes.append(box_json(b, "wall"));
  for (const auto& d : w.doors) {
    // Drawn closed: the panel runs from the hinge along its yaw.
    sim::BoxObstacle b;
    b.name = d.name;
    b.center_m = {d.hinge_m[0] + 0.5 * d.width_m * std::cos(d.yaw_rad),
                  d.hinge_m[1] + 0.5 * d.width_m * std::sin(d.yaw_rad), 0.5 * d.height_m};
    b.size_m = {d.width_m, d.thickness_m, d.height_m};
    b.yaw_rad = d.yaw_rad;
    boxes.append(box_json(b, "door"));
  }
  for (const auto& s : w.stairs) {
    // Step i covers [i, i+1] treads along the climb and rises to (i+1) risers; then the landing.
    const double c = std::cos(s.yaw_rad), sn = std::sin(s.yaw_rad);
    for (int i = 0; i <= s.steps; ++i) {
      const bool landing = i == s.steps;
      const double along0 = i * s.tread_m, len = landing ? s.landing_m : s.tread_m;
      const double h = landing ? s.landing_height_m() : (i + 1) * s.riser_m;
      sim::BoxObstacle b;
      b.name = s.name;
      b.center_m = {s.start_m[0] + (along0 + 0.5 * len) * c, s.start_m[1] + (along0 + 0.5 * len) * sn, 0.5 * h};
      b.size_m = {len, s.width_m, h};
      b.yaw_rad = s.yaw_rad;
      boxes.append(box_json(b, "stairs"));
    }
  }
  out["boxes"] = boxes;
  Json::Value objects(Json::arrayValue);
  for (const auto& o : w.objects) {
    Json::Value v;
    v["name"] = o.name;
    v["center"] = xyz(o.center_m.data());
    v["size"] = xyz(o.size_m.data());
    objects.append(v);
  }
  out["objects"] = objects;
  Json::Value regions(Json::arrayValue);
  for (const auto& r : w.regions) {
    Json::Value v;
    v["name"] = r.name;
    v["min"] = xyz(r.min_m.data());
    v["max"] = xyz(r.max_m.data());
    regions.append(v);
  }
  out["regions"] = regions;
  if (w.ceiling) out["ceiling_height"] = w.ceiling->height_m;
  Json::Value start(Json::arrayValue);
  start.append(w.robot_start_m[0]);
  start.append(w.robot_start_m[1]);
  start.append(w.robot_start_yaw_rad);
  out["robot_start"] = start;
  return out;
}

Json::Value pose_json(const sim::UrdfPose& p) {
  Json::Value v;
  v["xyz"] = xyz(p.xyz_m.data());
  Json::Value q(Json::arrayValue);
  for (double c : p.wxyz) q.append(c);
  v["wxyz"] = q;
  return v;
}

// A visual shape: a primitive's sizes, or a mesh's triangles as flat arrays
// (x, y, z per vertex in metres; three vertex indices per triangle).
Json::Value visual_json(const sim::UrdfShape& s) {
  static const char* const kTypes[] = {"box", "cylinder", "sphere", "mesh"};
  Json::Value v;
  v["type"] = kTypes[static_cast<int>(s.type)];
  v["size"] = xyz(s.size_m.data());
  v["origin"] = pose_json(s.origin);
  if (s.type == sim::UrdfShapeType::Mesh) {
    Json::Value vertices(Json::arrayValue), triangles(Json::arrayValue);
    // A tenth of a millimetre is enough to draw, and keeps the text short.
    for (float c : s.mesh.vertices_m) vertices.append(std::round(static_cast<double>(c) * 1e4) / 1e4);
    for (uint32_t i : s.mesh.triangles) triangles.append(i);
    v["vertices"] = vertices;
    v["triangles"] = triangles;
  }
  return v;
}

// A urdf_tree robot's links with their visual shapes and the joints between
// them, for the 3D view to pose by RobotState's joint positions.
void tree_json(const sim::UrdfTree& t, Json::Value& v) {
  static const char* const kJointTypes[] = {"revolute", "continuous", "prismatic", "fixed"};
  Json::Value links(Json::arrayValue), joints(Json::arrayValue);
  for (const auto& l : t.links) {
    Json::Value lv;
    lv["name"] = l.name;
    Json::Value rgba(Json::arrayValue);
    for (double c : l.rgba) rgba.append(c);
    lv["rgba"] = rgba;
    Json::Value visuals(Json::arrayValue);
    for (const auto& s : l.visuals) visuals.append(visual_json(s));
    lv["visuals"] = visuals;
    links.append(lv);
  }
  for (const auto& j : t.joints) {
    Json::Value jv;
    jv["name"] = j.name;
    jv["type"] = kJointTypes[static_cast<int>(j.type)];
    jv["parent"] = static_cast<Json::UInt>(j.parent);
    jv["child"] = static_cast<Json::UInt>(j.child);
    jv["origin"] = pose_json(j.origin);
    jv["axis"] = xyz(j.axis.data());
    joints.append(jv);
  }
  v["links"] = links;
  v["joints"] = joints;
}

Json::Value robot_json(const sim::RobotDescription& r) {
  Json::Value v;
  v["name"] = r.name;
  v["file"] = r.file;
  v["chassis_size"] = xyz(r.chassis.size_m.data());
  Json::Value cameras(Json::arrayValue);
  for (const auto& c : r.sensors.cameras) {
    Json::Value cv;
    cv["name"] = c.name;
    cv["position"] = xyz(c.mount.position_m.data());
    cv["rpy"] = xyz(c.mount.rpy_rad.data());
    cameras.append(cv);
  }
  v["cameras"] = cameras;
  if (r.tree) tree_json(*r.tree, v);
  return v;
}

Json::Value panel_definition_json(const panels::PanelDefinition& panel, uint32_t timeout_ms) {
  Json::Value v;
  v["name"] = panel.name;
  v["file"] = panel.file;
  v["publish_hz"] = panel.publish_hz;
  v["timeout_ms"] = timeout_ms;
  Json::Value controls(Json::arrayValue);
  for (const auto& c : panel.controls) {
    Json::Value cv;
    cv["name"] = c.name;
    cv["kind"] = c.kind == panels::ControlKind::Axis ? "axis" : c.kind == panels::ControlKind::Button ? "button" : "switch";
    cv["role"] = c.role == panels::ControlRole::Deadman ? "deadman" : c.role == panels::ControlRole::Estop ? "estop" : "";
    Json::Value positions(Json::arrayValue);
    for (const auto& p : c.positions) positions.append(p);
    cv["positions"] = positions;
    controls.append(cv);
  }
  v["controls"] = controls;
  // What the console shows back (PanelFeedback): the page draws these before any arrives.
  Json::Value leds(Json::arrayValue);
  for (const auto& l : panel.leds) leds.append(l.name);
  v["leds"] = leds;
  Json::Value displays(Json::arrayValue);
  for (const auto& d : panel.displays) {
    Json::Value dv;
    dv["name"] = d.name;
    dv["decimals"] = d.decimals;
    displays.append(dv);
  }
  v["displays"] = displays;
  return v;
}

Json::Value fault_buttons_json(const std::vector<FaultPreset>& presets, bool is_signed) {
  Json::Value v;
  v["signed"] = is_signed;
  Json::Value list(Json::arrayValue);
  for (const auto& p : presets) {
    Json::Value f;
    f["name"] = p.id;
    f["label"] = p.label;
    f["kind"] = p.kind;
    f["target"] = p.target;
    list.append(f);
  }
  v["faults"] = list;
  return v;
}

Json::Value publisher_json(const rise_msgs::Publisher& p) {
  Json::Value v;
  v["program"] = p.program;
  v["host"] = p.host;
  v["pid"] = p.pid;
  v["session"] = Json::Int64(p.session_id);
  v["started_utime"] = Json::Int64(p.started_utime);
  v["text"] = msgs::describe(p, msgs::wall_us());
  return v;
}

Json::Value panel_json(const rise_msgs::PanelState& m) {
  Json::Value v;
  v["utime"] = Json::Int64(m.utime);
  v["publisher"] = publisher_json(m.publisher);
  v["seq"] = Json::Int64(m.seq);
  v["panel_id"] = m.panel_id;
  v["failsafe"] = m.failsafe;
  Json::Value causes(Json::arrayValue);
  for (const msgs::FailsafeCause cause : msgs::kFailsafeCauses)
    if (msgs::has(m.failsafe_causes, cause)) causes.append(msgs::to_string(cause));
  v["failsafe_causes"] = causes;
  v["failsafe_reason"] = m.failsafe_reason;
  v["deadman"] = m.deadman;
  Json::Value axes(Json::objectValue), buttons(Json::objectValue), switches(Json::objectValue);
  for (const auto& a : m.axes) axes[a.name] = a.value;
  for (const auto& b : m.buttons) buttons[b.name] = b.pressed;
  for (const auto& s : m.switches) switches[s.name] = s.label;
  v["axes"] = axes;
  v["buttons"] = buttons;
  v["switches"] = switches;
  Json::Value sources(Json::arrayValue);
  for (const auto& s : m.sources) {
    Json::Value h;
    h["name"] = s.name;
    h["url"] = s.url;
    h["connected"] = s.connected;
    h["stale"] = s.stale;
    h["age_ms"] = s.last_frame_age_us < 0 ? -1.0 : static_cast<double>(s.last_frame_age_us) / 1000.0;
    h["frames_ok"] = Json::Int64(s.frames_ok);
    h["frames_bad"] = Json::Int64(s.frames_bad);
    h["status"] = s.status;
    h["bus_state"] = s.bus_state;
    h["down_reason"] = s.down_reason;
    sources.append(h);
  }
  v["sources"] = sources;
  Json::Value faults(Json::arrayValue);
  for (const auto& f : m.active_faults) faults.append(f);
  v["active_faults"] = faults;
  return v;
}

Json::Value robot_json(const rise_msgs::RobotState& m) {
  Json::Value v;
  v["utime"] = Json::Int64(m.utime);
  v["publisher"] = publisher_json(m.publisher);
  v["sim_time_s"] = m.sim_time_s;
  v["robot_id"] = m.robot_id;
  v["position"] = xyz(m.position_m);
  Json::Value q(Json::arrayValue);
  for (double c : m.orientation_wxyz) q.append(c);
  v["orientation_wxyz"] = q;
  const double w = m.orientation_wxyz[0], x = m.orientation_wxyz[1], y = m.orientation_wxyz[2],
               z = m.orientation_wxyz[3];
  v["yaw"] = std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
  v["speed_mps"] = m.linear_velocity_mps[0];
  v["yaw_rate_radps"] = m.angular_velocity_radps[2];
  v["damage"] = m.damage;
  v["battery"] = m.battery;
  v["motors_enabled"] = m.motors_enabled;
  v["stop_reason"] = m.stop_reason;
  v["gripper"] = xyz(m.gripper_position_m);
  Json::Value objects(Json::arrayValue);
  for (int i = 0; i < m.num_objects; ++i) {
    Json::Value o;
    o["name"] = m.object_names[static_cast<std::size_t>(i)];
    o["position"] = xyz(m.object_positions_m[static_cast<std::size_t>(i)].data());
    objects.append(o);
  }
  v["objects"] = objects;
  Json::Value contacts(Json::arrayValue);
  for (const auto& c : m.contacts) contacts.append(c);
  v["contacts"] = contacts;
  Json::Value faults(Json::arrayValue);
  for (const auto& f : m.active_faults) faults.append(f);
  v["active_faults"] = faults;  // "id: kind target", as rise-sim lists them
  Json::Value joints(Json::arrayValue);
  for (int i = 0; i < m.num_joints; ++i) {
    Json::Value j;
    j["name"] = m.joint_names[static_cast<std::size_t>(i)];
    j["position"] = m.joint_positions[static_cast<std::size_t>(i)];
    joints.append(j);
  }
  v["joints"] = joints;  // a urdf_tree robot's links are posed by them
  return v;
}

Json::Value task_status_json(const rise_msgs::TaskStatus& m) {
  Json::Value v;
  v["utime"] = Json::Int64(m.utime);
  v["publisher"] = publisher_json(m.publisher);
  v["training"] = m.training;
  v["node"] = m.node;
  v["task"] = m.task;
  v["attempt"] = m.attempt;
  v["tasks_done"] = m.tasks_done;
  v["state"] = m.state;
  v["task_time_s"] = m.task_time_s;
  v["time_limit_s"] = m.time_limit_s;
  v["score"] = m.score;
  v["events_fired"] = m.events_fired;
  v["success"] = m.success;
  v["end_reason"] = m.end_reason;
  v["training_score"] = m.training_score;
  return v;
}

Json::Value sim_event_json(const rise_msgs::SimEvent& m) {
  Json::Value v;
  v["utime"] = Json::Int64(m.utime);
  v["sim_time_s"] = m.sim_time_s;
  v["kind"] = m.kind;
  v["a"] = m.a;
  v["b"] = m.b;
  v["detail"] = m.detail;
  return v;
}

Json::Value task_event_json(const rise_msgs::TaskEvent& m) {
  Json::Value v;
  v["utime"] = Json::Int64(m.utime);
  v["task"] = m.task;
  v["attempt"] = m.attempt;
  v["task_time_s"] = m.task_time_s;
  v["name"] = m.name;
  v["kind"] = m.kind;
  v["points"] = m.points;
  v["score"] = m.score;
  v["detail"] = m.detail;
  return v;
}

Json::Value sound_cue_json(const rise_msgs::SoundCue& m) {
  Json::Value v;
  v["utime"] = Json::Int64(m.utime);
  v["sim_time_s"] = m.sim_time_s;
  v["name"] = m.name;
  v["sample"] = m.sample;
  v["continuous"] = m.continuous;
  v["gain"] = m.gain;
  v["pitch"] = m.pitch;
  v["detail"] = m.detail;
  return v;
}

Json::Value link_json(const TraineeLink& l) {
  Json::Value v;
  v["state"] = l.state;
  v["heard_ago_ms"] = static_cast<double>(l.heard_ago_us) / 1000.0;
  v["arrival_age_ms"] = static_cast<double>(l.arrival_age_us) / 1000.0;
  if (l.clock) {
    v["clock_offset_ms"] = static_cast<double>(l.clock->offset_us) / 1000.0;
    v["clock_delay_ms"] = static_cast<double>(l.clock->delay_us) / 1000.0;
    v["clock_host"] = l.clock_host;
  }
  return v;
}

Json::Value panel_feedback_json(const rise_msgs::PanelFeedback& m) {
  Json::Value v;
  v["utime"] = Json::Int64(m.utime);
  v["panel_id"] = m.panel_id;
  Json::Value leds(Json::objectValue);
  for (std::size_t i = 0; i < m.led_names.size() && i < m.led_on.size(); ++i) leds[m.led_names[i]] = m.led_on[i] != 0;
  v["leds"] = leds;
  Json::Value displays(Json::objectValue);
  for (std::size_t i = 0; i < m.display_names.size() && i < m.display_values.size(); ++i)
    displays[m.display_names[i]] = m.display_values[i];
  v["displays"] = displays;
  v["buzzer"] = m.buzzer == 1 ? "on" : m.buzzer == 2 ? "beep" : "off";
  v["rumble"] = m.rumble;
  return v;
}

}  // namespace rise::instructor
