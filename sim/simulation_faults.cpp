// Physics and sensor faults (sim/sim_fault.hpp) on the robots: setting,
// clearing and ending them, and their effects on the drive, the grip and
// the joints' break loads.

#include <algorithm>
#include <string_view>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

// Which drive side a fault target names: 0 left, 1 right.
std::optional<std::size_t> side_of(const std::string& target) {
  if (target == "left" || target == "track_left" || target == "wheel_fl" || target == "wheel_rl") return 0;
  if (target == "right" || target == "track_right" || target == "wheel_fr" || target == "wheel_rr") return 1;
  return std::nullopt;
}

double value_or(const PhysicsFault& f, double fallback) { return f.value > 0.0 ? f.value : fallback; }

}  // namespace

Simulation::Impl::Breakable* Simulation::Impl::find_breakable(std::size_t robot, const std::string& name) {
  for (auto& b : breakables)
    if (b.name == name && (b.robot == static_cast<int>(robot) || b.robot < 0)) return &b;
  return nullptr;
}

// Drive and grip factors and break loads from every robot's faults.
void Simulation::Impl::apply_fault_effects() {
  for (auto& b : breakables)
    if (b.nominal_break_load_nm >= 0.0) b.break_load_nm = b.nominal_break_load_nm;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    Robot& r = *robots[i];
    r.drive_factor = {1.0, 1.0};
    r.grip_factor = {1.0, 1.0};
    for (const PhysicsFault& f : r.faults) {
      const auto side = side_of(f.target);
      switch (f.kind) {
        case SimFaultKind::MotorFailure: r.drive_factor[*side] = 0.0; break;
        case SimFaultKind::MotorWeakness: r.drive_factor[*side] *= std::clamp(value_or(f, 0.5), 0.0, 1.0); break;
        case SimFaultKind::TrackSlip: r.grip_factor[*side] *= std::clamp(value_or(f, 0.2), 0.0, 1.0); break;
        case SimFaultKind::WeakJoint:
          if (Breakable* b = find_breakable(i, f.target)) {
            if (b->nominal_break_load_nm < 0.0) b->nominal_break_load_nm = b->break_load_nm;
            b->break_load_nm *= std::clamp(value_or(f, 0.3), 0.0, 1.0);
          }
          break;
        default: break;  // sensor faults: read by the sensors
      }
    }
  }
}

std::string Simulation::Impl::set_fault(std::size_t robot, PhysicsFault f) {
  if (robot >= robots.size()) return "no robot #" + std::to_string(robot);
  Robot& r = *robots[robot];
  if (f.id.empty()) return "a fault needs an id";
  switch (f.kind) {
    case SimFaultKind::MotorFailure:
    case SimFaultKind::MotorWeakness:
    case SimFaultKind::TrackSlip:
      if (!side_of(f.target)) return std::string(to_string(f.kind)) + ": target '" + f.target + "' is not left or right";
      break;
    case SimFaultKind::WeakJoint:
      if (!find_breakable(robot, f.target)) return "weak_joint: robot '" + r.id + "' has no joint '" + f.target + "'";
      break;
    case SimFaultKind::CameraBlackout: {
      bool found = f.target.empty();
      for (const auto& c : r.desc.sensors.cameras) found = found || c.name == f.target;
      if (!found) return "camera_blackout: robot '" + r.id + "' has no camera '" + f.target + "'";
      break;
    }
    case SimFaultKind::ScannerNoise:
    case SimFaultKind::ScannerDropout:
      if (!f.target.empty() && f.target != "laser") return std::string(to_string(f.kind)) + ": target is laser";
      break;
  }
  f.start_s = time_s();
  f.end_s = f.duration_s > 0.0 ? f.start_s + f.duration_s : 0.0;
  std::erase_if(r.faults, [&](const PhysicsFault& g) { return g.id == f.id; });
  emit(SimEventKind::FaultInjected, r.id, f.id, std::string(to_string(f.kind)) + " " + f.target);
  r.faults.push_back(std::move(f));
  apply_fault_effects();
  return {};
}

std::size_t Simulation::Impl::clear_fault(std::size_t robot, const std::string& id, const char* why) {
  if (robot >= robots.size()) return 0;
  Robot& r = *robots[robot];
  std::size_t n = 0;
  for (auto it = r.faults.begin(); it != r.faults.end();) {
    const bool ended = std::string_view(why) == "ended";
    if (ended ? (it->end_s > 0.0 && time_s() >= it->end_s - 1e-9) : (id.empty() || it->id == id)) {
      emit(SimEventKind::FaultCleared, r.id, it->id, std::string(to_string(it->kind)) + " " + it->target + ": " + why);
      it = r.faults.erase(it);
      ++n;
    } else {
      ++it;
    }
  }
  if (n > 0) apply_fault_effects();
  return n;
}

std::string Simulation::set_fault(std::size_t robot, PhysicsFault fault) {
  try {
    return impl_->set_fault(robot, std::move(fault));
  } catch (const std::exception& e) {
    return e.what();
  }
}

std::size_t Simulation::clear_fault(std::size_t robot, const std::string& id) {
  return impl_->clear_fault(robot, id, "cleared");
}

std::vector<PhysicsFault> Simulation::faults(std::size_t robot) const {
  if (robot >= impl_->robots.size()) return {};
  return impl_->robots[robot]->faults;
}

bool Simulation::camera_blacked_out(const std::string& camera, std::size_t robot) const {
  if (robot >= impl_->robots.size()) return false;
  for (const auto& f : impl_->robots[robot]->faults)
    if (f.kind == SimFaultKind::CameraBlackout && (f.target.empty() || f.target == camera)) return true;
  return false;
}

}  // namespace rise::sim
