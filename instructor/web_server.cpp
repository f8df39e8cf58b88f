#include "instructor/web_server.hpp"

// Eigen before httplib: httplib pulls in <resolv.h>, whose `_res` macro
// breaks Eigen's parameters of that name.
#include "sim/robot_description.hpp"

#include <httplib.h>
#include <json/json.h>
#include <lcm/lcm-cpp.hpp>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <map>
#include <mutex>
#include <regex>
#include <set>
#include <stdexcept>
#include <thread>

#include "hil/io/host_port.hpp"
#include "hil/panel_state_message.hpp"
#include "instructor/scenario.hpp"
#include "instructor/trainee_directory.hpp"
#include "instructor/virtual_panel.hpp"
#include "msgs/clock.hpp"
#include "msgs/command_auth.hpp"
#include "msgs/publisher_session.hpp"
#include "panels/panel_definition.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimControl.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/TaskEvent.hpp"
#include "rise_msgs/TaskStatus.hpp"
#include "sim/world_description.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;

namespace {

int64_t monotonic_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string to_text(const Json::Value& v) {
  Json::StreamWriterBuilder b;
  b["indentation"] = "";
  return Json::writeString(b, v);
}

// Comparison whose time does not depend on where the strings differ.
bool same_token(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i % (b.empty() ? 1 : b.size())]);
  return diff == 0 && !b.empty();
}

std::string cookie_token(const httplib::Request& req) {
  const std::string cookies = req.get_header_value("Cookie");
  const std::string key = "rise_token=";
  for (std::size_t pos = 0; pos < cookies.size();) {
    std::size_t end = cookies.find(';', pos);
    if (end == std::string::npos) end = cookies.size();
    std::string part = cookies.substr(pos, end - pos);
    part.erase(0, part.find_first_not_of(' '));
    if (part.rfind(key, 0) == 0) return part.substr(key.size());
    pos = end + 1;
  }
  return "";
}

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

// The static scene as boxes the pages draw (world frame, z up), plus the
// regions and the movable objects' start.
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

// What the 3D view draws of the robot: its chassis box and its camera
// mounts (base frame, x forward, z up; rpy in radians).
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

template <class Message>
std::optional<Message> decode(const lcm::ReceiveBuffer* rbuf) {
  Message m;
  if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return std::nullopt;
  return m;
}

bool valid_id(const std::string& id) {
  static const std::regex re("[A-Za-z0-9_.-]{1,64}");
  return std::regex_match(id, re);
}

}  // namespace

const std::vector<FaultPreset>& default_fault_presets() {
  // Input faults act on the rise console's controls, wire faults on its
  // source "console", transport faults on panel_state, physics and sensor
  // faults on the robot (rise-sim).
  static const std::vector<FaultPreset> presets = {
      {"stick-stuck", "drive stick stuck at 0.6", "stuck_at", "drive_y", 0.6, 0.0, 0.0},
      {"stick-drift", "drive stick drifts right", "drift", "drive_x", 0.0, 0.2, 0.0},
      {"stick-noise", "drive stick noise", "noise", "drive_y", 0.1, 0.0, 0.0},
      {"deadman-intermittent", "dead-man intermittent", "intermittent", "deadman", 0.5, 0.1, 0.0},
      {"can-drop", "CAN frames dropped (50 %)", "can_drop", "console", 0.5, 0.0, 0.0},
      {"can-bus-off", "CAN bus-off", "can_bus_off", "console", 0.0, 0.0, 5.0},
      {"lcm-loss", "PanelState loss (30 %)", "lcm_loss", "panel_state", 0.3, 0.0, 0.0},
      {"left-motor", "left motor failure", "motor_failure", "left", 0.0, 0.0, 0.0},
      {"track-slip", "track slip", "track_slip", "left", 0.5, 0.0, 0.0},
      {"camera-blackout", "camera blackout", "camera_blackout", "", 0.0, 0.0, 10.0},
  };
  return presets;
}

struct WebServer::Impl {
  WebServerSettings settings;
  sim::WorldDescription world;
  std::string world_text;
  panels::PanelDefinition panel;
  lcm::LCM lcm;
  httplib::Server http;
  std::atomic<bool> running{false};
  std::thread http_thread, lcm_thread, virtual_thread;
  int bound_port = 0;

  // Latest message per channel, and the recent discrete events.
  struct Latest {
    std::string kind;
    std::string trainee;
    Json::Value value;
    uint64_t version = 0;
  };
  std::mutex mutex;
  std::condition_variable changed;
  uint64_t version = 0;
  std::map<std::string, Latest> latest;
  std::deque<std::pair<uint64_t, Json::Value>> events;

  // Other processes publishing the trainees' states (this process's own
  // virtual panels come back over LCM too and are not "others").
  msgs::PublisherWatch publishers{msgs::this_publisher().session_id};

  // Virtual panels by trainee id.
  std::mutex virtual_mutex;
  std::map<std::string, std::unique_ptr<VirtualPanel>> virtual_panels;
  int64_t sim_control_seq = 0;
  std::optional<msgs::InstructorKey> key;
  // Checks the fault commands meant for this server's virtual panels (they
  // come back over LCM like any receiver's; the LCM thread owns it).
  std::unique_ptr<msgs::CommandVerifier> verifier;

  // Running scenarios by trainee id.
  struct ScenarioRun {
    std::string name;
    std::string file;
    uint64_t seed = 0;
    std::unique_ptr<process::ChildProcess> process;
  };
  std::mutex scenario_mutex;
  std::map<std::string, ScenarioRun> scenarios;
  // Children are started from this one long-lived thread: a child dies with
  // the thread that forked it (PR_SET_PDEATHSIG), and request threads come and go.
  std::thread launcher_thread;
  std::mutex launcher_mutex;
  std::condition_variable launcher_cv;
  std::deque<std::packaged_task<void()>> launcher_tasks;

  void launcher_loop() {
    for (;;) {
      std::packaged_task<void()> task;
      {
        std::unique_lock lock(launcher_mutex);
        launcher_cv.wait(lock, [&] { return !launcher_tasks.empty() || !running; });
        if (launcher_tasks.empty()) return;
        task = std::move(launcher_tasks.front());
        launcher_tasks.pop_front();
      }
      task();
    }
  }
  /// Runs `f` on the launcher thread and waits for it; rethrows what it threw.
  void on_launcher(std::function<void()> f) {
    std::packaged_task<void()> task(std::move(f));
    auto done = task.get_future();
    {
      std::lock_guard lock(launcher_mutex);
      launcher_tasks.push_back(std::move(task));
    }
    launcher_cv.notify_one();
    done.get();
  }

  explicit Impl(WebServerSettings s) : settings(std::move(s)), lcm(settings.lcm_url) {
    if (settings.token.empty()) throw std::runtime_error("a token is required (--token or --token-file)");
    if (!lcm.good()) throw std::runtime_error("cannot open LCM at " + settings.lcm_url);
    if (!fs::is_regular_file(fs::path(settings.web_dir) / "index.html"))
      throw std::runtime_error(settings.web_dir + ": no index.html (build the pages: npm ci && npm run build in instructor/web)");
    world = settings.world_file.empty() ? sim::default_world() : sim::load_world_description(settings.world_file);
    Json::Value w = world_json(world);
    if (!settings.robot_file.empty()) w["robot"] = robot_json(sim::load_robot_description(settings.robot_file));
    world_text = to_text(w);
    panel = panels::load_panel_definition(settings.panel_file);
    (void)virtual_definition(panel, settings.virtual_timeout_ms);  // fails here, not on the first page
    if (settings.push_hz < 20.0) throw std::runtime_error("push_hz must be at least 20");
    if (!settings.instructor_key_file.empty()) {
      key = msgs::load_instructor_key(settings.instructor_key_file);
      verifier = std::make_unique<msgs::CommandVerifier>(*key);
    }
  }

  void store(const std::string& channel, const std::string& trainee, const std::string& kind, Json::Value value,
             bool is_event) {
    std::lock_guard lock(mutex);
    ++version;
    if (is_event) {
      value["trainee"] = trainee;
      value["channel_kind"] = kind;
      events.emplace_back(version, std::move(value));
      while (events.size() > 200) events.pop_front();
    } else {
      Latest& l = latest[channel];
      l.kind = kind;
      l.trainee = trainee;
      l.value = std::move(value);
      l.version = version;
    }
    changed.notify_all();
  }

  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    static const std::regex re("rise/([^/]+)/([a-z_]+)");
    std::smatch m;
    if (!std::regex_match(channel, m, re)) return;
    const std::string trainee = m[1], kind = m[2];
    if (kind == "fault_command") {
      if (auto c = decode<rise_msgs::FaultCommand>(rbuf)) on_fault_command(trainee, *c);
    } else if (kind == "panel_state") {
      if (auto s = decode<rise_msgs::PanelState>(rbuf)) {
        watch_publisher(channel, trainee, s->publisher);
        store(channel, trainee, kind, panel_json(*s), false);
      }
    } else if (kind == "robot_state") {
      if (auto s = decode<rise_msgs::RobotState>(rbuf)) {
        watch_publisher(channel, trainee, s->publisher);
        store(channel, trainee, kind, robot_json(*s), false);
      }
    } else if (kind == "task_status") {
      if (auto s = decode<rise_msgs::TaskStatus>(rbuf)) {
        watch_publisher(channel, trainee, s->publisher);
        store(channel, trainee, kind, task_status_json(*s), false);
      }
    } else if (kind == "sim_event") {
      if (auto s = decode<rise_msgs::SimEvent>(rbuf)) store(channel, trainee, kind, sim_event_json(*s), true);
    } else if (kind == "task_event") {
      if (auto s = decode<rise_msgs::TaskEvent>(rbuf)) store(channel, trainee, kind, task_event_json(*s), true);
    }
  }

  // A second publisher beside one of this server's virtual panels is told
  // to the program (it logs it); trainees_json lists every duplicate.
  void watch_publisher(const std::string& channel, const std::string& trainee, const rise_msgs::Publisher& p) {
    const auto other = publishers.observe(channel, p, monotonic_us());
    if (!other || !settings.on_duplicate_publisher) return;
    bool ours = false;
    {
      std::lock_guard lock(virtual_mutex);
      ours = channel == hil::channel(trainee, "panel_state") && virtual_panels.count(trainee) > 0;
    }
    if (ours)
      settings.on_duplicate_publisher("another publisher on " + channel + ": " +
                                      msgs::describe(other->publisher, msgs::wall_us()) +
                                      ", beside this server's virtual panel for '" + trainee + "'");
  }

  // A virtual panel is a receiver like rise-hild: it takes signed input
  // faults and reports the rest; commands for other trainees are not ours.
  void on_fault_command(const std::string& trainee, const rise_msgs::FaultCommand& c) {
    std::lock_guard lock(virtual_mutex);
    const auto it = virtual_panels.find(trainee);
    if (it == virtual_panels.end()) return;
    const int64_t now = monotonic_us();
    if (c.trainee_id != trainee) return it->second->note_rejected("for trainee '" + c.trainee_id + "'", now);
    if (!verifier) return it->second->note_rejected("no instructor key on this server", now);
    const auto verdict = verifier->check(c, msgs::wall_us());
    if (verdict != msgs::Verdict::Accepted) return it->second->note_rejected(msgs::to_string(verdict), now);
    // Other layers' faults (physics, sensors) are rise-sim's: not an error here.
    const std::string why = it->second->apply(c, now);
    (void)why;
  }

  void lcm_loop() {
    const int fd = lcm.getFileno();
    while (running) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 50) > 0 && (p.revents & POLLIN)) lcm.handle();
    }
  }

  // Publishes every virtual panel's state at the definition's rate, so a
  // page that stops sending is failsafe within one period after its timeout.
  void virtual_loop() {
    const double hz = panel.publish_hz > 0 ? panel.publish_hz : 100.0;
    const auto period = std::chrono::microseconds(static_cast<int64_t>(1e6 / hz));
    auto next = std::chrono::steady_clock::now();
    while (running) {
      next += period;
      std::this_thread::sleep_until(next);
      std::vector<std::pair<std::string, rise_msgs::PanelState>> out;
      {
        std::lock_guard lock(virtual_mutex);
        const int64_t now = monotonic_us(), utime = wall_us();
        for (auto& [id, vp] : virtual_panels) out.emplace_back(id, vp->state(id, now, utime));
      }
      for (auto& [id, state] : out) lcm.publish(hil::channel(id, "panel_state"), &state);
    }
  }

  Json::Value trainees_json() {
    std::lock_guard lock(mutex);
    std::map<std::string, Json::Value> by_id;
    for (const auto& [channel, l] : latest) {
      Json::Value& t = by_id[l.trainee];
      t["id"] = l.trainee;
      t[l.kind] = l.value;
    }
    std::set<std::string> virtual_ids;
    {
      std::lock_guard vlock(virtual_mutex);
      for (const auto& [id, vp] : virtual_panels) {
        by_id[id]["id"] = id;
        by_id[id]["virtual_panel"] = true;
        virtual_ids.insert(id);
      }
    }
    // Every channel with more than one process publishing on it now.
    std::map<std::string, std::vector<rise_msgs::Publisher>> by_channel;
    for (const auto& o : publishers.others(monotonic_us())) by_channel[o.channel].push_back(o.publisher);
    for (auto& [channel, list] : by_channel) {
      const auto parts = TraineeDirectory::split_channel(channel);
      if (!parts) continue;
      const auto& [id, what] = *parts;
      if (what == "panel_state" && virtual_ids.count(id)) list.push_back(msgs::this_publisher());
      if (list.size() < 2) continue;
      Json::Value& d = by_id[id]["duplicate_publishers"][what];
      for (const auto& p : list) d.append(publisher_json(p));
    }
    Json::Value out(Json::arrayValue);
    for (auto& [id, t] : by_id) out.append(t);
    return out;
  }

  Json::Value reports_json() const {
    Json::Value out(Json::arrayValue);
    if (settings.reports_dir.empty() || !fs::is_directory(settings.reports_dir)) return out;
    std::vector<std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(settings.reports_dir)) {
      if (!e.is_regular_file()) continue;
      const auto ext = e.path().extension().string();
      if (ext == ".html" || ext == ".json") files.push_back(fs::relative(e.path(), settings.reports_dir).string());
    }
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      Json::Value v;
      v["path"] = f;
      v["url"] = "/reports/" + f;
      out.append(v);
    }
    return out;
  }

  bool authorised(const httplib::Request& req) const {
    if (req.has_param("token") && same_token(req.get_param_value("token"), settings.token)) return true;
    const std::string auth = req.get_header_value("Authorization");
    if (auth.rfind("Bearer ", 0) == 0 && same_token(auth.substr(7), settings.token)) return true;
    if (same_token(req.get_header_value("X-Rise-Token"), settings.token)) return true;
    return same_token(cookie_token(req), settings.token);
  }

  static void reply_json(httplib::Response& res, const Json::Value& v, int status = 200) {
    res.status = status;
    res.set_content(to_text(v), "application/json");
  }
  static void reply_error(httplib::Response& res, int status, const std::string& message) {
    Json::Value v;
    v["error"] = message;
    reply_json(res, v, status);
  }

  static std::optional<Json::Value> parse_body(const httplib::Request& req, std::string* error) {
    Json::CharReaderBuilder b;
    Json::Value v;
    std::string errs;
    std::unique_ptr<Json::CharReader> reader(b.newCharReader());
    if (!reader->parse(req.body.data(), req.body.data() + req.body.size(), &v, &errs)) {
      *error = "body: " + errs;
      return std::nullopt;
    }
    return v;
  }

  void handle_virtual(const httplib::Request& req, httplib::Response& res) {
    const std::string id = req.matches[1];
    if (!valid_id(id)) return reply_error(res, 400, "trainee id '" + id + "': letters, digits, _ . - only");
    std::string error;
    const auto body = parse_body(req, &error);
    if (!body || !body->isObject()) return reply_error(res, 400, error.empty() ? "body: not a JSON object" : error);
    VirtualControls controls;
    try {
      for (const auto& name : (*body)["axes"].getMemberNames()) controls.axes[name] = (*body)["axes"][name].asFloat();
      for (const auto& name : (*body)["buttons"].getMemberNames())
        controls.buttons[name] = (*body)["buttons"][name].asBool();
      for (const auto& name : (*body)["switches"].getMemberNames())
        controls.switches[name] = (*body)["switches"][name].asString();
    } catch (const std::exception& e) {
      return reply_error(res, 400, std::string("body: ") + e.what());
    }
    std::lock_guard lock(virtual_mutex);
    auto& vp = virtual_panels[id];
    if (!vp) {
      // One publisher per station: not beside a console's rise-hild (or another server's panel).
      for (const auto& o : publishers.others(monotonic_us()))
        if (o.channel == hil::channel(id, "panel_state")) {
          virtual_panels.erase(id);
          return reply_error(res, 409, o.channel + " is already published by " +
                                           msgs::describe(o.publisher, msgs::wall_us()) +
                                           ": a virtual panel there would mix with it");
        }
      vp = std::make_unique<VirtualPanel>(panel, settings.virtual_timeout_ms, req.remote_addr);
    }
    if (auto e = vp->update(controls, monotonic_us())) return reply_error(res, 400, *e);
    res.status = 204;
  }

  void handle_sim_control(const httplib::Request& req, httplib::Response& res) {
    const std::string id = req.matches[1], command = req.matches[2];
    if (!valid_id(id)) return reply_error(res, 400, "trainee id '" + id + "': letters, digits, _ . - only");
    rise_msgs::SimControl c;
    c.utime = wall_us();
    c.issuer = "rise-instructor";
    {
      std::lock_guard lock(virtual_mutex);
      c.seq = ++sim_control_seq;
    }
    c.command = command;
    c.steps = command == "step" ? 100 : 0;
    lcm.publish(hil::channel(id, "sim_control"), &c);
    Json::Value v;
    v["published"] = hil::channel(id, "sim_control");
    v["command"] = command;
    v["seq"] = Json::Int64(c.seq);
    reply_json(res, v);
  }

  // Inject or clear one fault: a FaultCommand signed with the instructor key
  // on rise/<trainee>/fault_command. The body names a preset ("fault") or
  // gives the fields (kind, target, value, rate, duration_s, seed).
  void handle_fault(const httplib::Request& req, httplib::Response& res, const std::string& action) {
    if (!key) return reply_error(res, 503, "no instructor key (rise-instructor serve --instructor-key FILE)");
    std::string error;
    const auto body = parse_body(req, &error);
    if (!body || !body->isObject()) return reply_error(res, 400, error.empty() ? "body: not a JSON object" : error);
    const std::string id = (*body).get("trainee", "").asString();
    if (!valid_id(id)) return reply_error(res, 400, "trainee '" + id + "': letters, digits, _ . - only");
    rise_msgs::FaultCommand c{};
    c.utime = 0;
    c.nonce = 0;
    c.issuer = settings.issuer;
    c.trainee_id = id;
    c.action = action;
    const std::string name = (*body).get("fault", "").asString();
    c.fault_id = name == "*" ? "" : name;
    if (action == "inject") {
      const auto& presets = default_fault_presets();
      const auto it = std::find_if(presets.begin(), presets.end(), [&](const FaultPreset& p) { return p.id == name; });
      if (it != presets.end()) {
        c.kind = it->kind;
        c.target = it->target;
        c.value = it->value;
        c.rate = it->rate;
        c.duration_s = it->duration_s;
      } else if ((*body).isMember("kind")) {
        c.kind = (*body)["kind"].asString();
        c.target = (*body).get("target", "").asString();
        c.value = (*body).get("value", 0.0).asDouble();
        c.rate = (*body).get("rate", 0.0).asDouble();
        c.duration_s = (*body).get("duration_s", 0.0).asDouble();
      } else {
        return reply_error(res, 400, "fault '" + name + "': no such preset, and no kind given");
      }
      if (c.fault_id.empty()) return reply_error(res, 400, "fault: a name is required to inject");
      c.seed = (*body).get("seed", 1).asInt64();
    }
    msgs::sign(c, *key);
    lcm.publish(hil::channel(id, "fault_command"), &c);
    Json::Value v;
    v["published"] = hil::channel(id, "fault_command");
    v["action"] = action;
    v["fault_id"] = c.fault_id;
    v["kind"] = c.kind;
    v["target"] = c.target;
    v["nonce"] = Json::Int64(c.nonce);
    reply_json(res, v);
  }

  // The scenario files offered: name (the file's `scenario:`), file, faults,
  // and which trainees run one now.
  Json::Value scenarios_json() {
    Json::Value v;
    v["enabled"] = !settings.scenario_program.empty() && key.has_value();
    Json::Value files(Json::arrayValue);
    if (!settings.scenarios_dir.empty() && fs::is_directory(settings.scenarios_dir)) {
      std::vector<fs::path> paths;
      for (const auto& e : fs::directory_iterator(settings.scenarios_dir))
        if (e.is_regular_file() && e.path().extension() == ".yaml") paths.push_back(e.path());
      std::sort(paths.begin(), paths.end());
      for (const auto& p : paths) {
        Json::Value f;
        f["file"] = p.filename().string();
        try {
          const Scenario s = load_scenario(p.string());
          f["name"] = s.name;
          f["faults"] = static_cast<Json::UInt64>(s.faults.size());
          f["seed"] = static_cast<Json::UInt64>(s.seed);
        } catch (const std::exception& e) {
          f["error"] = e.what();
        }
        files.append(f);
      }
    }
    v["files"] = files;
    Json::Value running(Json::objectValue);
    std::lock_guard lock(scenario_mutex);
    for (auto& [id, run] : scenarios) {
      if (!run.process->running()) continue;
      Json::Value r;
      r["file"] = run.file;
      r["seed"] = static_cast<Json::UInt64>(run.seed);
      r["pid"] = run.process->pid();
      running[id] = r;
    }
    v["running"] = running;
    return v;
  }

  void handle_scenario(const httplib::Request& req, httplib::Response& res, bool start) {
    if (settings.scenario_program.empty() || settings.scenarios_dir.empty())
      return reply_error(res, 503, "scenario control is off (rise-instructor serve --scenarios-dir DIR)");
    if (!key) return reply_error(res, 503, "no instructor key (rise-instructor serve --instructor-key FILE)");
    std::string error;
    const auto body = parse_body(req, &error);
    if (!body || !body->isObject()) return reply_error(res, 400, error.empty() ? "body: not a JSON object" : error);
    const std::string id = body->get("trainee", "").asString();
    if (!valid_id(id)) return reply_error(res, 400, "trainee '" + id + "': letters, digits, _ . - only");
    std::lock_guard lock(scenario_mutex);
    auto it = scenarios.find(id);
    if (it != scenarios.end()) {
      // Stopping (or replacing) a run: SIGINT, so it clears its auto_clear faults.
      if (it->second.process->running()) it->second.process->stop(5000);
      scenarios.erase(it);
    }
    Json::Value v;
    v["trainee"] = id;
    if (!start) {
      v["stopped"] = true;
      return reply_json(res, v);
    }
    const std::string file = body->get("file", "").asString();
    const fs::path path = fs::path(settings.scenarios_dir) / file;
    if (file.empty() || file.find('/') != std::string::npos || path.extension() != ".yaml" || !fs::is_regular_file(path))
      return reply_error(res, 400, "scenario file '" + file + "': not a .yaml file in " + settings.scenarios_dir);
    ScenarioRun run;
    run.file = file;
    try {
      const Scenario s = load_scenario(path.string());
      run.name = s.name;
      run.seed = body->isMember("seed") ? body->get("seed", 0).asUInt64() : s.seed;
    } catch (const std::exception& e) {
      return reply_error(res, 400, e.what());
    }
    std::vector<std::string> argv{settings.scenario_program,
                                  "scenario",
                                  path.string(),
                                  "--trainee",
                                  id,
                                  "--seed",
                                  std::to_string(run.seed),
                                  "--lcm",
                                  settings.lcm_url,
                                  "--instructor-key",
                                  settings.instructor_key_file,
                                  "--issuer",
                                  settings.issuer};
    try {
      on_launcher([&] { run.process = std::make_unique<process::ChildProcess>(argv, ""); });
    } catch (const std::exception& e) {
      return reply_error(res, 500, e.what());
    }
    v["file"] = file;
    v["name"] = run.name;
    v["seed"] = static_cast<Json::UInt64>(run.seed);
    v["pid"] = run.process->pid();
    scenarios[id] = std::move(run);
    reply_json(res, v);
  }

  // One SSE stream: the channels that changed since the client's last push,
  // and the new events, at most push_hz times a second, at least every second.
  void handle_stream(const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-cache");
    auto last = std::make_shared<uint64_t>(0);
    const auto period = std::chrono::microseconds(static_cast<int64_t>(1e6 / settings.push_hz));
    auto next = std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
    res.set_chunked_content_provider("text/event-stream", [this, last, period, next](size_t, httplib::DataSink& sink) {
      if (!running) return false;
      std::this_thread::sleep_until(*next);
      *next = std::max(*next + period, std::chrono::steady_clock::now());
      Json::Value update;
      {
        std::unique_lock lock(mutex);
        changed.wait_for(lock, std::chrono::seconds(1), [&] { return version > *last || !running; });
        if (!running) return false;
        Json::Value channels(Json::objectValue);
        for (const auto& [channel, l] : latest) {
          if (l.version <= *last) continue;
          Json::Value c;
          c["trainee"] = l.trainee;
          c["kind"] = l.kind;
          c["value"] = l.value;
          channels[channel] = c;
        }
        Json::Value evs(Json::arrayValue);
        for (const auto& [v, e] : events)
          if (v > *last) evs.append(e);
        update["channels"] = channels;
        update["events"] = evs;
        update["server_utime"] = Json::Int64(wall_us());
        *last = version;
      }
      const std::string text = "data: " + to_text(update) + "\n\n";
      return sink.write(text.data(), text.size());
    });
  }

  void routes() {
    const std::size_t threads = std::max<std::size_t>(settings.http_threads, 4);
    http.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
    http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      if (authorised(req)) {
        // The pages load their scripts by plain URLs: a cookie carries the token on.
        if (req.has_param("token"))
          res.set_header("Set-Cookie", "rise_token=" + settings.token + "; Path=/; HttpOnly; SameSite=Strict");
        return httplib::Server::HandlerResponse::Unhandled;
      }
      reply_error(res, 401, "token required (?token=, Authorization: Bearer, or X-Rise-Token)");
      return httplib::Server::HandlerResponse::Handled;
    });
    if (!http.set_mount_point("/", settings.web_dir))
      throw std::runtime_error(settings.web_dir + ": cannot serve this folder");
    // Reports: only the .html / .json files /api/reports lists, never
    // whatever else the folder holds (a key file, a journal).
    http.Get(R"(/reports/(.+))", [this](const httplib::Request& req, httplib::Response& res) {
      const std::string rel = req.matches[1];
      const fs::path path = fs::path(settings.reports_dir) / rel;
      const auto ext = path.extension().string();
      const bool inside = !settings.reports_dir.empty() && rel.find("..") == std::string::npos && rel[0] != '/';
      if (!inside || (ext != ".html" && ext != ".json") || !fs::is_regular_file(path))
        return reply_error(res, 404, "no report '" + rel + "'");
      std::ifstream in(path, std::ios::binary);
      std::string body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      res.set_content(body, ext == ".html" ? "text/html" : "application/json");
    });
    http.Get("/api/world", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(world_text, "application/json");
    });
    http.Get("/api/trainees", [this](const httplib::Request&, httplib::Response& res) { reply_json(res, trainees_json()); });
    http.Get("/api/reports", [this](const httplib::Request&, httplib::Response& res) { reply_json(res, reports_json()); });
    http.Get("/api/panel", [this](const httplib::Request&, httplib::Response& res) {
      Json::Value v;
      v["name"] = panel.name;
      v["file"] = panel.file;
      v["publish_hz"] = panel.publish_hz;
      v["timeout_ms"] = settings.virtual_timeout_ms;
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
      reply_json(res, v);
    });
    http.Get("/api/stream", [this](const httplib::Request& req, httplib::Response& res) { handle_stream(req, res); });
    http.Post(R"(/api/virtual/([^/]+))", [this](const httplib::Request& req, httplib::Response& res) {
      handle_virtual(req, res);
    });
    http.Post(R"(/api/virtual/([^/]+)/close)", [this](const httplib::Request& req, httplib::Response& res) {
      std::lock_guard lock(virtual_mutex);
      const auto it = virtual_panels.find(req.matches[1]);
      if (it == virtual_panels.end()) return reply_error(res, 404, "no virtual panel '" + std::string(req.matches[1]) + "'");
      it->second->disconnect(monotonic_us());
      res.status = 204;
    });
    http.Get("/api/faults", [this](const httplib::Request&, httplib::Response& res) {
      Json::Value v;
      v["signed"] = key.has_value();
      Json::Value list(Json::arrayValue);
      for (const auto& p : default_fault_presets()) {
        Json::Value f;
        f["name"] = p.id;
        f["label"] = p.label;
        f["kind"] = p.kind;
        f["target"] = p.target;
        list.append(f);
      }
      v["faults"] = list;
      reply_json(res, v);
    });
    http.Post("/api/fault/inject", [this](const httplib::Request& req, httplib::Response& res) {
      handle_fault(req, res, "inject");
    });
    http.Post("/api/fault/clear", [this](const httplib::Request& req, httplib::Response& res) {
      handle_fault(req, res, "clear");
    });
    http.Get("/api/scenarios", [this](const httplib::Request&, httplib::Response& res) { reply_json(res, scenarios_json()); });
    http.Post("/api/scenario/start", [this](const httplib::Request& req, httplib::Response& res) {
      handle_scenario(req, res, true);
    });
    http.Post("/api/scenario/stop", [this](const httplib::Request& req, httplib::Response& res) {
      handle_scenario(req, res, false);
    });
    http.Post(R"(/api/sim/([^/]+)/(pause|resume|step|reset))",
              [this](const httplib::Request& req, httplib::Response& res) { handle_sim_control(req, res); });
  }
};

WebServer::WebServer(WebServerSettings settings) : impl_(std::make_unique<Impl>(std::move(settings))) {}

WebServer::~WebServer() { stop(); }

void WebServer::start() {
  Impl& d = *impl_;
  d.routes();
  d.lcm.subscribeFunction("rise/.*/(panel_state|robot_state|sim_event|task_status|task_event|fault_command)",
                          +[](const lcm::ReceiveBuffer* rbuf, const std::string& channel, Impl* self) {
                            self->on_message(rbuf, channel);
                          },
                          &d);
  // cpp-httplib 0.11's default options set SO_REUSEPORT, with which a second
  // server binds the same port and the kernel splits the connections between
  // the two. SO_REUSEADDR only: a restart still gets its port back while old
  // connections sit in TIME_WAIT, and a port in use fails with EADDRINUSE.
  d.http.set_socket_options([](socket_t sock) {
    const int on = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  });
  errno = 0;
  if (d.settings.port == 0) {
    d.bound_port = d.http.bind_to_any_port(d.settings.host);
    if (d.bound_port < 0) throw std::runtime_error("cannot bind " + d.settings.host);
  } else {
    const std::string address = io::format_host_port(d.settings.host, static_cast<uint16_t>(d.settings.port));
    if (!d.http.bind_to_port(d.settings.host, d.settings.port)) {
      // cpp-httplib closes the socket after the failed bind() or listen(), which keeps errno.
      if (errno == EADDRINUSE) throw std::runtime_error(address + ": address in use");
      throw std::runtime_error("cannot bind " + address);
    }
    d.bound_port = d.settings.port;
  }
  d.running = true;
  d.lcm_thread = std::thread([&d] { d.lcm_loop(); });
  d.virtual_thread = std::thread([&d] { d.virtual_loop(); });
  d.launcher_thread = std::thread([&d] { d.launcher_loop(); });
  d.http_thread = std::thread([&d] { d.http.listen_after_bind(); });
}

void WebServer::stop() {
  Impl& d = *impl_;
  if (!d.running.exchange(false)) return;
  d.changed.notify_all();
  d.launcher_cv.notify_all();
  d.http.stop();
  {
    std::lock_guard lock(d.scenario_mutex);
    for (auto& [id, run] : d.scenarios)
      if (run.process->running()) run.process->stop(5000);
    d.scenarios.clear();
  }
  for (auto* t : {&d.http_thread, &d.lcm_thread, &d.virtual_thread, &d.launcher_thread})
    if (t->joinable()) t->join();
}

int WebServer::port() const { return impl_->bound_port; }

}  // namespace rise::instructor
