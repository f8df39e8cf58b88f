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

#include "msgs/channels.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"

namespace rise::instructor_test {

inline const std::string kLcm = rise::msgs::kDefaultLcmUrl;

/// What arrives on one trainee's channels, in order.
class TraineePeer {
 public:
  explicit TraineePeer(std::string id) : id_(std::move(id)), lcm_(kLcm) {
    lcm_.subscribe(rise::msgs::robot_state_channel(id_), &TraineePeer::on_robot, this)->setQueueCapacity(1000);
    lcm_.subscribe(rise::msgs::panel_state_channel(id_), &TraineePeer::on_panel, this)->setQueueCapacity(1000);
    lcm_.subscribe(rise::msgs::fault_command_channel(id_), &TraineePeer::on_fault, this)->setQueueCapacity(100);
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

  std::vector<rise_msgs::RobotState> robot;
  std::vector<rise_msgs::PanelState> panels;  ///< only those with a "virtual" source
  std::vector<rise_msgs::PanelState> daemon_panels;  ///< those of rise-hild (other sources)
  std::vector<rise_msgs::FaultCommand> faults;

 private:
  void on_robot(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::RobotState* m) { robot.push_back(*m); }
  void on_panel(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) {
    if (!m->sources.empty() && m->sources[0].name == "virtual") panels.push_back(*m);
    else if (!m->sources.empty()) daemon_panels.push_back(*m);
  }
  void on_fault(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::FaultCommand* m) { faults.push_back(*m); }

  std::string id_;
  lcm::LCM lcm_;
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
