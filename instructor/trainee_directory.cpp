#include "instructor/trainee_directory.hpp"

#include <algorithm>

#include "msgs/channels.hpp"
#include "msgs/lcm_decode.hpp"

namespace rise::instructor {

bool TraineeDirectory::on_message(const std::string& channel, const void* data, int size, int64_t now_us) {
  const auto parts = msgs::parse_station_channel(channel);
  if (!parts) return false;
  // Not a structured binding: clang 14 (the fuzz targets' compiler) cannot capture one.
  const std::string& id = parts->trainee_id;
  const std::string& what = parts->what;
  const auto take = [&](auto slot, auto message) {
    if (!msgs::decode_message(data, size, message)) return false;
    TraineeRow& row = rows_[id];
    row.id = id;
    row.last_seen_us = now_us;
    const auto seen = std::find_if(row.publishers.begin(), row.publishers.end(), [&](const SeenPublisher& p) {
      return p.what == what && p.publisher.session_id == message.publisher.session_id;
    });
    if (seen != row.publishers.end()) seen->last_seen_us = now_us;
    else row.publishers.push_back({what, message.publisher, now_us});
    slot(row) = std::move(message);
    return true;
  };
  if (what == "panel_state") return take([](TraineeRow& r) -> auto& { return r.panel; }, rise_msgs::PanelState{});
  if (what == "robot_state") return take([](TraineeRow& r) -> auto& { return r.robot; }, rise_msgs::RobotState{});
  if (what == "task_status") return take([](TraineeRow& r) -> auto& { return r.task; }, rise_msgs::TaskStatus{});
  return false;
}

std::vector<std::string> TraineeRow::duplicated(int64_t now_us, int64_t window_us) const {
  std::map<std::string, int> count;
  for (const auto& p : publishers)
    if (now_us - p.last_seen_us <= window_us) ++count[p.what];
  std::vector<std::string> out;
  for (const auto& [what, n] : count)
    if (n > 1) out.push_back(what);
  return out;
}

std::vector<TraineeRow> TraineeDirectory::rows() const {
  std::vector<TraineeRow> out;
  for (const auto& [id, row] : rows_) out.push_back(row);
  return out;
}

}  // namespace rise::instructor
