#pragma once

// The instructor tests' side of the LCM network and of the HTTP server.

#include <httplib.h>
#include <json/json.h>
#include <lcm/lcm-cpp.hpp>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"

namespace rise::instructor_test {

inline const std::string kLcm = "udpm://239.255.76.67:7667?ttl=0";

/// What arrives on one trainee's channels, in order.
class TraineePeer {
 public:
  explicit TraineePeer(std::string id) : id_(std::move(id)), lcm_(kLcm) {
    lcm_.subscribe("rise/" + id_ + "/robot_state", &TraineePeer::on_robot, this)->setQueueCapacity(1000);
    lcm_.subscribe("rise/" + id_ + "/panel_state", &TraineePeer::on_panel, this)->setQueueCapacity(1000);
    lcm_.subscribe("rise/" + id_ + "/fault_command", &TraineePeer::on_fault, this)->setQueueCapacity(100);
  }
  bool good() { return lcm_.good(); }
  lcm::LCM& lcm() { return lcm_; }

  /// Handles messages until `done` holds or timeout_ms passes; true if it held.
  /// `each` runs between handle calls (e.g. to publish a scripted panel).
  bool wait_until(const std::function<bool()>& done, int timeout_ms, const std::function<void()>& each = {}) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (!done()) {
      if (std::chrono::steady_clock::now() >= end) return false;
      if (each) each();
      lcm_.handleTimeout(10);
    }
    return true;
  }

  /// A scripted console: dead-man held, drive mode, slow, the stick forward.
  void publish_driving_panel(float forward) {
    rise_msgs::PanelState p;
    p.utime = 0;
    p.panel_id = "scripted";
    p.trainee_id = id_;
    p.seq = ++seq_;
    p.failsafe = false;
    p.deadman = true;
    p.axes = {{"drive_y", forward}, {"drive_x", 0.0f}};
    p.num_axes = 2;
    p.buttons = {{"estop", false}, {"deadman", true}};
    p.num_buttons = 2;
    p.switches = {{"mode", 0, "drive"}, {"speed", 1, "medium"}};
    p.num_switches = 2;
    p.num_sources = 0;
    p.num_faults = 0;
    lcm_.publish("rise/" + id_ + "/panel_state", &p);
  }

  std::vector<rise_msgs::RobotState> robot;
  std::vector<rise_msgs::PanelState> panels;  ///< only those with a "virtual" source
  std::vector<rise_msgs::FaultCommand> faults;

 private:
  void on_robot(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::RobotState* m) { robot.push_back(*m); }
  void on_panel(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) {
    if (!m->sources.empty() && m->sources[0].name == "virtual") panels.push_back(*m);
  }
  void on_fault(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::FaultCommand* m) { faults.push_back(*m); }

  std::string id_;
  lcm::LCM lcm_;
  int64_t seq_ = 0;
};

inline double distance_xy(const rise_msgs::RobotState& a, const rise_msgs::RobotState& b) {
  return std::hypot(a.position_m[0] - b.position_m[0], a.position_m[1] - b.position_m[1]);
}

/// A port the kernel says is free on loopback right now.
inline int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

inline Json::Value parse_json(const std::string& text) {
  Json::CharReaderBuilder b;
  Json::Value v;
  std::string errs;
  std::unique_ptr<Json::CharReader> r(b.newCharReader());
  if (!r->parse(text.data(), text.data() + text.size(), &v, &errs)) return Json::Value();
  return v;
}

}  // namespace rise::instructor_test
