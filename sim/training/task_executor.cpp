#include "sim/training/task_executor.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace rise::sim::training {
namespace {

bool inside(const Region& g, const std::array<double, 3>& p) {
  for (std::size_t k = 0; k < 3; ++k)
    if (p[k] < g.min_m[k] || p[k] > g.max_m[k]) return false;
  return true;
}

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", s);
  return buf;
}

// The arm's gripper parts as rise::sim names them (sim/simulation_robots.cpp).
bool is_gripper_part(const std::string& part) { return part == "gripper_jaw" || part == "gripper_finger"; }

}  // namespace

SimEventInput from_sim(const SimEvent& e) { return {e.time_s, to_string(e.kind), e.a, e.b, e.detail}; }

RobotSample sample_of(const Simulation& sim, const WorldDescription& world, std::size_t robot) {
  const auto snap = sim.snapshot(robot);
  RobotSample s;
  s.time_s = snap.time_s;
  s.position_m = snap.position_m;
  s.yaw_rad = snap.yaw_rad();
  s.damage = snap.damage;
  s.gripper_position_m = snap.gripper_position_m;
  for (const auto& o : world.objects) s.objects.push_back({o.name, sim.object_position_m(o.name)});
  return s;
}

TaskExecutor::TaskExecutor(TaskDescription task, WorldDescription world, std::string robot_id)
    : task_(std::move(task)), world_(std::move(world)), robot_id_(std::move(robot_id)) {
  check_against_world(task_, world_);
  result_.task = task_.name;
  result_.title = task_.title;
  result_.task_file = task_.file;
  result_.world_file = world_.file;
  result_.time_limit_s = task_.time_limit_s;
  for (const auto& e : task_.events) result_.counts[e.name] = 0;
}

std::vector<FiredEvent> TaskExecutor::take_fired() {
  std::vector<FiredEvent> out;
  out.swap(fresh_);
  return out;
}

const Region* TaskExecutor::region(const std::string& name) const {
  for (const auto& g : task_.regions)
    if (g.name == name) return &g;
  for (const auto& g : world_.regions)
    if (g.name == name) return &g;
  return nullptr;
}

bool TaskExecutor::is_robot(const std::string& name) const {
  if (!robot_id_.empty()) return name == robot_id_;
  for (const auto& d : world_.doors)
    if (d.name == name) return false;
  return !name.empty();
}

std::string TaskExecutor::part_of(const std::string& name) const {
  if (robot_id_.empty()) {
    const auto slash = name.find('/');
    return slash == std::string::npos ? name : name.substr(slash + 1);
  }
  const std::string prefix = robot_id_ + "/";
  return name.rfind(prefix, 0) == 0 ? name.substr(prefix.size()) : name;
}

void TaskExecutor::fire(const TaskEventSpec& spec, const std::string& detail) {
  if (result_.finished) return;
  int& count = result_.counts[spec.name];
  if (spec.max_count > 0 && count >= spec.max_count) return;
  ++count;
  result_.score += spec.points;
  FiredEvent f{result_.time_s, spec.name, to_string(spec.kind), spec.points, result_.score, detail};
  result_.events.push_back(f);
  fresh_.push_back(f);
  for (const auto& end : task_.end_on)
    if (end == spec.name) {
      finish("event " + spec.name);
      if (task_.success.empty()) result_.success = spec.points >= 0;
    }
}

void TaskExecutor::finish(const std::string& reason) {
  if (result_.finished) return;
  result_.finished = true;
  result_.end_reason = reason;
  // Without `success:` a task succeeds by ending on a non-penalty end_on event (set by fire()).
  if (task_.success.empty()) {
    result_.success = false;
  } else {
    result_.success = true;
    for (const auto& s : task_.success) result_.success = result_.success && result_.counts[s] > 0;
  }
}

void TaskExecutor::abort(const std::string& reason) { finish(reason); }

void TaskExecutor::advance_time(double sim_time_s) {
  if (!t0_s_) t0_s_ = sim_time_s;
  result_.time_s = std::max(result_.time_s, sim_time_s - *t0_s_);
  for (const auto& e : task_.events)
    if (e.kind == TaskEventKind::TimeExceeded && result_.time_s >= e.after_s - 1e-9)
      fire(e, "task time " + seconds(result_.time_s) + " >= " + seconds(e.after_s));
  if (result_.time_s >= task_.time_limit_s - 1e-9) finish("time limit");
}

void TaskExecutor::on_sim_event(const SimEventInput& ev) {
  if (result_.finished) return;
  advance_time(ev.time_s);
  if (result_.finished) return;
  // Collisions name the robot's part first: "chassis" (one robot) or "<id>/chassis".
  const bool robot_part_a = ev.kind.rfind("collision_", 0) == 0 &&
                            (robot_id_.empty() || ev.a.find('/') == std::string::npos ||
                             ev.a.rfind(robot_id_ + "/", 0) == 0);
  if (ev.kind == "collision_started" && robot_part_a) ++result_.collisions;
  for (std::size_t i = 0; i < task_.events.size(); ++i) {
    const auto& e = task_.events[i];
    switch (e.kind) {
      case TaskEventKind::ReachRegion:
        if (ev.kind == "region_entered" && ev.b == e.region && is_robot(ev.a)) fire(e, ev.a + " entered " + e.region);
        break;
      case TaskEventKind::TouchObject:
        if (ev.kind == "collision_started" && robot_part_a && ev.b == e.object)
          fire(e, part_of(ev.a) + " touched " + e.object + (ev.detail.empty() ? "" : " (" + ev.detail + ")"));
        break;
      case TaskEventKind::RobotDamaged:
        if (ev.kind == "joint_broken" && is_robot(ev.a))
          fire(e, "joint " + ev.b + " broken" + (ev.detail.empty() ? "" : " (" + ev.detail + ")"));
        break;
      case TaskEventKind::RobotDisabled:
        if (ev.kind == "tipped_over" && is_robot(ev.a)) fire(e, ev.a + " tipped over");
        break;
      case TaskEventKind::Collision: {
        if (!robot_part_a) break;
        bool excepted = false;
        for (const auto& x : e.except) excepted = excepted || x == ev.b;
        if (excepted) break;
        if (!e.per_second && ev.kind == "collision_started")
          fire(e, part_of(ev.a) + " hit " + ev.b + (ev.detail.empty() ? "" : " (" + ev.detail + ")"));
        if (e.per_second && ev.kind == "collision_continues")
          fire(e, part_of(ev.a) + " against " + ev.b + " for " + ev.detail);
        break;
      }
      case TaskEventKind::NeutralizeObject: {
        if (e.within_m > 0 || !robot_part_a || ev.b != e.object || !is_gripper_part(part_of(ev.a))) break;
        auto& parts = gripper_contacts_[e.object];
        if (ev.kind == "collision_started") {
          if (parts.empty()) gripper_contact_since_s_[e.object] = result_.time_s;
          parts.insert(part_of(ev.a));
        } else if (ev.kind == "collision_stopped") {
          parts.erase(part_of(ev.a));
        }
        break;
      }
      default:
        break;
    }
  }
  // Contact that has lasted hold_s neutralizes (checked on events and states).
  for (const auto& e : task_.events) {
    if (e.kind != TaskEventKind::NeutralizeObject || e.within_m > 0) continue;
    const auto& parts = gripper_contacts_[e.object];
    if (!parts.empty() && result_.time_s - gripper_contact_since_s_[e.object] >= e.hold_s - 1e-9)
      fire(e, "gripper on " + e.object + " for " + seconds(result_.time_s - gripper_contact_since_s_[e.object]));
  }
}

void TaskExecutor::on_state(const RobotSample& s) {
  if (result_.finished) return;
  advance_time(s.time_s);
  if (result_.finished) return;
  result_.damage = s.damage;
  const auto object = [&](const std::string& name) -> const ObjectSample* {
    for (const auto& o : s.objects)
      if (o.name == name) return &o;
    return nullptr;
  };
  // A condition that must hold continuously for hold_s: true → fire once held long enough.
  const auto hold = [&](std::size_t i, bool holds, const std::string& what) {
    const auto& e = task_.events[i];
    if (!holds) {
      held_since_s_.erase(i);
      return;
    }
    const double since = held_since_s_.emplace(i, result_.time_s).first->second;
    if (result_.time_s - since >= e.hold_s - 1e-9) fire(e, what + " for " + seconds(result_.time_s - since));
  };
  for (std::size_t i = 0; i < task_.events.size() && !result_.finished; ++i) {
    const auto& e = task_.events[i];
    switch (e.kind) {
      case TaskEventKind::ReachRegion: {
        // World regions come as region_entered; the task's own from the base position.
        bool task_region = false;
        for (const auto& g : task_.regions) task_region = task_region || g.name == e.region;
        if (task_region && inside(*region(e.region), s.position_m)) fire(e, "base inside " + e.region);
        break;
      }
      case TaskEventKind::ObjectInRegion: {
        const auto* o = object(e.object);
        hold(i, o && inside(*region(e.region), o->position_m), e.object + " in " + e.region);
        break;
      }
      case TaskEventKind::NeutralizeObject: {
        if (e.within_m > 0) {
          const auto* o = object(e.object);
          bool near = false;
          if (o) {
            const double dx = s.gripper_position_m[0] - o->position_m[0];
            const double dy = s.gripper_position_m[1] - o->position_m[1];
            const double dz = s.gripper_position_m[2] - o->position_m[2];
            near = std::sqrt(dx * dx + dy * dy + dz * dz) <= e.within_m;
          }
          char what[96];
          std::snprintf(what, sizeof what, "gripper within %.2f m of ", e.within_m);
          hold(i, near, what + e.object);
        } else {
          const auto& parts = gripper_contacts_[e.object];
          if (!parts.empty() && result_.time_s - gripper_contact_since_s_[e.object] >= e.hold_s - 1e-9)
            fire(e, "gripper on " + e.object + " for " + seconds(result_.time_s - gripper_contact_since_s_[e.object]));
        }
        break;
      }
      case TaskEventKind::RobotDisabled:
        if (s.damage >= 1.0) fire(e, "damage " + std::to_string(s.damage));
        break;
      default:
        break;
    }
  }
  if (last_track_s_ < 0 || result_.time_s - last_track_s_ >= 0.1 - 1e-9 || result_.finished) {
    last_track_s_ = result_.time_s;
    result_.trajectory.push_back({result_.time_s, s.position_m[0], s.position_m[1], s.yaw_rad});
    std::set<std::string> wanted;
    for (const auto& e : task_.events)
      if (!e.object.empty()) wanted.insert(e.object);
    for (const auto& o : s.objects)
      if (wanted.count(o.name))
        result_.object_tracks[o.name].push_back({result_.time_s, o.position_m[0], o.position_m[1], 0.0});
  }
}

}  // namespace rise::sim::training
