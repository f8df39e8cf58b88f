#include "sim/training/task_result.hpp"

namespace rise::sim::training {

std::optional<double> TaskResult::field(const std::string& name) const {
  if (name == "score") return score;
  if (name == "time_s") return time_s;
  if (name == "success") return success ? 1.0 : 0.0;
  if (name == "damage") return damage;
  if (name == "collisions") return collisions;
  if (name == "attempt") return attempt;
  if (name.rfind("events.", 0) == 0) {
    const auto it = counts.find(name.substr(7));
    if (it != counts.end()) return it->second;
  }
  return std::nullopt;
}

}  // namespace rise::sim::training
