// The semantic events a scenario engine scores, detected after each step:
// collisions (started, continuing, stopped), doors, regions, stairs,
// tip-over, moved objects.

#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

// Event thresholds (the brief's scoring rules).
constexpr double kDoorOpenRad = 10.0 * M_PI / 180.0;
constexpr double kDoorClosedRad = 5.0 * M_PI / 180.0;
constexpr double kObjectMovedM = 0.05;
constexpr double kTipCos = 0.5;      // cos 60°
constexpr double kUprightCos = 0.7;  // cos ~45°: re-arms the tip-over event
constexpr int kCollisionReleaseSteps = 50;  // contact gone this long → collision stopped
constexpr int kCollisionContinueSteps = 1000;  // a lasting collision is reported again every second
constexpr std::size_t kMaxPendingEvents = 4096;

}  // namespace

const char* to_string(SimEventKind kind) {
  switch (kind) {
    case SimEventKind::CollisionStarted: return "collision_started";
    case SimEventKind::CollisionStopped: return "collision_stopped";
    case SimEventKind::CollisionContinues: return "collision_continues";
    case SimEventKind::DoorOpened: return "door_opened";
    case SimEventKind::DoorClosed: return "door_closed";
    case SimEventKind::JointBroken: return "joint_broken";
    case SimEventKind::RegionEntered: return "region_entered";
    case SimEventKind::RegionLeft: return "region_left";
    case SimEventKind::ObjectMoved: return "object_moved";
    case SimEventKind::StairsClimbed: return "stairs_climbed";
    case SimEventKind::TippedOver: return "tipped_over";
    case SimEventKind::FaultInjected: return "fault_injected";
    case SimEventKind::FaultCleared: return "fault_cleared";
  }
  return "unknown";
}

void Simulation::Impl::emit(SimEventKind kind, std::string a, std::string b, std::string detail) {
  if (events.size() >= kMaxPendingEvents) return;  // nobody drains them: do not grow without bound
  events.push_back(SimEvent{time_s(), kind, std::move(a), std::move(b), std::move(detail)});
}

void Simulation::Impl::update_events() {
  update_collision_events();
  update_door_events();
  for (auto& r : robots) update_robot_events(*r);
  update_object_events();
}

// Collisions: started on first contact, stopped after a quiet spell so
// that a track rolling over step noses does not chatter.
// A collision that lasts is reported again each second it goes on
// (the seed's "touch continues"), detail = seconds since it started.
void Simulation::Impl::update_collision_events() {
  for (const auto& [key, touch] : seen) {
    const auto it = active.find(key);
    if (it == active.end()) {
      active.emplace(key, ActiveCollision{steps, steps, touch.robot_a, touch.robot_b});
      char speed[32];
      std::snprintf(speed, sizeof speed, "%.2f m/s", touch.impact_mps);
      emit(SimEventKind::CollisionStarted, key.first, key.second, std::string("impact ") + speed);
      const std::string detail = "collision_started " + key.first + " " + key.second + " " + speed;
      for (const int ri : {touch.robot_a, touch.robot_b})
        if (ri >= 0) cue(*robots[static_cast<std::size_t>(ri)], SoundTrigger::CollisionStarted, detail, touch.impact_mps);
    } else {
      it->second.last_seen = steps;
    }
  }
  for (auto it = active.begin(); it != active.end();) {
    const ActiveCollision& c = it->second;
    if (steps - c.last_seen >= kCollisionReleaseSteps) {
      emit(SimEventKind::CollisionStopped, it->first.first, it->first.second);
      it = active.erase(it);
      continue;
    }
    const int64_t lasted = steps - c.started;
    if (lasted > 0 && lasted % kCollisionContinueSteps == 0) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%.0f s", static_cast<double>(lasted) * kStepS);
      emit(SimEventKind::CollisionContinues, it->first.first, it->first.second, seconds);
    }
    ++it;
  }
}

void Simulation::Impl::update_door_events() {
  for (auto& d : doors) {
    const Breakable& h = breakables[d.hinge];
    if (h.broken()) continue;
    const double angle = std::fabs(dJointGetHingeAngle(h.joint));
    if (!d.open && angle > kDoorOpenRad) {
      d.open = true;
      emit(SimEventKind::DoorOpened, d.desc->name);
      door_cue(d.desc->name, SoundTrigger::DoorOpened, "door_opened " + d.desc->name);
    } else if (d.open && angle < kDoorClosedRad) {
      d.open = false;
      emit(SimEventKind::DoorClosed, d.desc->name);
      door_cue(d.desc->name, SoundTrigger::DoorClosed, "door_closed " + d.desc->name);
    }
  }
}

void Simulation::Impl::update_object_events() {
  for (auto& o : objects) {
    if (o.moved) continue;
    const dReal* q = dBodyGetPosition(o.body);
    const auto& c = o.desc->center_m;
    const double d = std::sqrt((q[0] - c[0]) * (q[0] - c[0]) + (q[1] - c[1]) * (q[1] - c[1]) +
                               (q[2] - c[2]) * (q[2] - c[2]));
    if (d > kObjectMovedM) {
      o.moved = true;
      emit(SimEventKind::ObjectMoved, o.desc->name, {}, "moved " + std::to_string(static_cast<int>(d * 100)) + " cm");
    }
  }
}

// Regions, stairs and tip-over: each robot's own.
void Simulation::Impl::update_robot_events(Robot& r) {
  const dReal* p = dBodyGetPosition(r.chassis);
  for (const auto& g : world_desc.regions) {
    bool inside = true;
    for (std::size_t k = 0; k < 3; ++k) inside = inside && p[k] >= g.min_m[k] && p[k] <= g.max_m[k];
    const bool was = r.inside_regions.count(g.name) > 0;
    if (inside && !was) {
      r.inside_regions.insert(g.name);
      emit(SimEventKind::RegionEntered, r.id, g.name);
      cue(r, SoundTrigger::RegionEntered, "region_entered " + g.name);
    } else if (!inside && was) {
      r.inside_regions.erase(g.name);
      emit(SimEventKind::RegionLeft, r.id, g.name);
    }
  }
  for (const auto& s : world_desc.stairs) {
    // Base position in the stairs' frame: along the climb, across it.
    const double dx = p[0] - s.start_m[0], dy = p[1] - s.start_m[1];
    const double along = std::cos(s.yaw_rad) * dx + std::sin(s.yaw_rad) * dy;
    const double across = -std::sin(s.yaw_rad) * dx + std::cos(s.yaw_rad) * dy;
    const double landing0 = s.steps * s.tread_m;
    const bool on = p[2] > s.landing_height_m() && along >= landing0 && along <= landing0 + s.landing_m &&
                    std::fabs(across) <= s.width_m / 2;
    const bool was = r.climbed.count(s.name) > 0;
    if (on && !was) {
      r.climbed.insert(s.name);
      emit(SimEventKind::StairsClimbed, r.id, s.name);
      cue(r, SoundTrigger::StairsClimbed, "stairs_climbed " + s.name);
    } else if (!on && was && p[2] < s.landing_height_m()) {
      r.climbed.erase(s.name);  // back down: climbing again counts again
    }
  }
  const dReal* R = dBodyGetRotation(r.chassis);
  const double up = R[10];  // world z of the base's z axis
  if (!r.tipped && up < kTipCos) {
    r.tipped = true;
    const auto tilt_deg = static_cast<int>(std::acos(std::clamp(up, -1.0, 1.0)) * 180.0 / M_PI);
    const std::string tilt = "tilt " + std::to_string(tilt_deg) + "°";
    emit(SimEventKind::TippedOver, r.id, {}, tilt);
    cue(r, SoundTrigger::TippedOver, "tipped_over " + tilt);
  } else if (r.tipped && up > kUprightCos) {
    r.tipped = false;
  }
}

std::vector<SimEvent> Simulation::take_events() {
  std::vector<SimEvent> out;
  out.swap(impl_->events);
  return out;
}

}  // namespace rise::sim
