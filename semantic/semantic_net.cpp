#include "semantic/semantic_net.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace rise::semantic {
namespace {

// Axis-aligned xy bounds of an entity's footprint (its yawed box).
struct Box2 {
  Eigen::Vector2d lo, hi;
};

Box2 footprint(const Entity& e) {
  const double c = std::abs(std::cos(e.yaw_rad)), s = std::abs(std::sin(e.yaw_rad));
  const Eigen::Vector2d half(0.5 * (c * e.size_m.x() + s * e.size_m.y()), 0.5 * (s * e.size_m.x() + c * e.size_m.y()));
  return {e.position_m.head<2>() - half, e.position_m.head<2>() + half};
}

bool overlaps(const Box2& a, const Box2& b) {
  return a.lo.x() < b.hi.x() && b.lo.x() < a.hi.x() && a.lo.y() < b.hi.y() && b.lo.y() < a.hi.y();
}

bool has_direction(EntityKind k) {
  return k == EntityKind::Wall || k == EntityKind::Door || k == EntityKind::Stairs || k == EntityKind::Step;
}

// Angle between two line directions, folded to 0..π/2.
double line_angle(double a, double b) {
  double d = std::abs(std::remainder(a - b, M_PI));
  return std::min(d, M_PI - d);
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", std::abs(v) < 5e-5 ? 0.0 : v);
  return buf;
}

std::string vec(const Eigen::Vector3d& v) { return "[" + number(v.x()) + ", " + number(v.y()) + ", " + number(v.z()) + "]"; }
std::string vec(const Eigen::Vector2d& v) { return "[" + number(v.x()) + ", " + number(v.y()) + "]"; }

}  // namespace

const char* to_string(EntityKind kind) {
  switch (kind) {
    case EntityKind::Floor: return "floor";
    case EntityKind::Ceiling: return "ceiling";
    case EntityKind::Wall: return "wall";
    case EntityKind::Door: return "door";
    case EntityKind::Stairs: return "stairs";
    case EntityKind::Step: return "step";
    case EntityKind::Obstacle: return "obstacle";
  }
  return "?";
}

const char* to_string(Relation relation) {
  switch (relation) {
    case Relation::Parallel: return "parallel";
    case Relation::Orthogonal: return "orthogonal";
    case Relation::Above: return "above";
    case Relation::Under: return "under";
    case Relation::EqualHeight: return "equal_height";
    case Relation::Inside: return "inside";
  }
  return "?";
}

SemanticNet::SemanticNet(Segmentation segmentation, const SemanticNetSettings& st) : seg_(std::move(segmentation)) {
  const double z0 = seg_.floor.height_m;
  const auto add = [&](EntityKind kind, int index, Eigen::Vector3d pos, Eigen::Vector3d size, double yaw) {
    const int id = static_cast<int>(entities_.size());
    int n = 0;
    for (const auto& e : entities_) n += e.kind == kind;
    std::string name = to_string(kind);
    if (kind != EntityKind::Floor && kind != EntityKind::Ceiling) name += "_" + std::to_string(n);
    entities_.push_back({id, kind, name, index, pos, size, yaw});
  };
  const auto& f = seg_.floor;
  add(EntityKind::Floor, 0, {(f.min_m.x() + f.max_m.x()) / 2, (f.min_m.y() + f.max_m.y()) / 2, z0},
      {f.max_m.x() - f.min_m.x(), f.max_m.y() - f.min_m.y(), 0.0}, 0.0);
  if (seg_.ceiling.found) {
    const auto& c = seg_.ceiling;
    add(EntityKind::Ceiling, 0, {(c.min_m.x() + c.max_m.x()) / 2, (c.min_m.y() + c.max_m.y()) / 2, c.height_m},
        {c.max_m.x() - c.min_m.x(), c.max_m.y() - c.min_m.y(), 0.0}, 0.0);
  }
  for (std::size_t i = 0; i < seg_.walls.size(); ++i) {
    const auto& w = seg_.walls[i];
    const Eigen::Vector2d m = (w.from_m + w.to_m) / 2, d = w.direction();
    add(EntityKind::Wall, static_cast<int>(i), {m.x(), m.y(), z0 + w.height_m / 2},
        {w.length_m(), w.thickness_m, w.height_m}, std::atan2(d.y(), d.x()));
  }
  for (std::size_t i = 0; i < seg_.doors.size(); ++i) {
    const auto& d = seg_.doors[i];
    add(EntityKind::Door, static_cast<int>(i), {d.center_m.x(), d.center_m.y(), z0 + d.height_m / 2},
        {d.width_m, d.wall_thickness_m, d.height_m}, d.yaw_rad);
  }
  for (std::size_t i = 0; i < seg_.stairs.size(); ++i) {
    const auto& s = seg_.stairs[i];
    const Eigen::Vector2d d(std::cos(s.yaw_rad), std::sin(s.yaw_rad));
    const double length = s.steps * s.tread_m + s.landing_m, height = s.steps * s.riser_m;
    const Eigen::Vector2d m = s.start_m + d * length / 2;
    add(EntityKind::Stairs, static_cast<int>(i), {m.x(), m.y(), z0 + height / 2}, {length, s.width_m, height},
        s.yaw_rad);
  }
  // Each tread: its middle at its height.
  struct StepOf {
    int stairs_id, step;
  };
  std::vector<StepOf> steps;
  for (const int sid : of_kind(EntityKind::Stairs)) {
    const auto& s = seg_.stairs[static_cast<std::size_t>(entity(sid).index)];
    const Eigen::Vector2d d(std::cos(s.yaw_rad), std::sin(s.yaw_rad));
    for (int k = 1; k <= s.steps; ++k) {
      const Eigen::Vector2d m = s.start_m + d * (k - 0.5) * s.tread_m;
      add(EntityKind::Step, entity(sid).index, {m.x(), m.y(), z0 + k * s.riser_m}, {s.tread_m, s.width_m, 0.0}, s.yaw_rad);
      entities_.back().name = entity(sid).name + "_step_" + std::to_string(k);
      steps.push_back({sid, k});
    }
  }
  for (std::size_t i = 0; i < seg_.obstacles.size(); ++i) {
    const auto& o = seg_.obstacles[i];
    add(EntityKind::Obstacle, static_cast<int>(i), o.center_m, o.size_m, o.yaw_rad);
  }

  // Relations from the geometry.
  const auto bottom = [](const Entity& e) { return e.position_m.z() - e.size_m.z() / 2; };
  const auto top = [](const Entity& e) { return e.position_m.z() + e.size_m.z() / 2; };
  for (const auto& a : entities_)
    for (const auto& b : entities_) {
      if (a.id == b.id) continue;
      if (has_direction(a.kind) && has_direction(b.kind)) {
        const double ang = line_angle(a.yaw_rad, b.yaw_rad);
        if (ang <= st.angle_tolerance_rad) links_.push_back({a.id, Relation::Parallel, b.id});
        if (std::abs(ang - M_PI / 2) <= st.angle_tolerance_rad) links_.push_back({a.id, Relation::Orthogonal, b.id});
      }
      if ((a.kind == EntityKind::Floor || a.kind == EntityKind::Ceiling) &&
          (b.kind == EntityKind::Floor || b.kind == EntityKind::Ceiling))
        links_.push_back({a.id, Relation::Parallel, b.id});
      // Above / under: one's bottom at or over the other's top, footprints overlapping.
      if (overlaps(footprint(a), footprint(b)) || a.kind == EntityKind::Floor || b.kind == EntityKind::Floor ||
          a.kind == EntityKind::Ceiling || b.kind == EntityKind::Ceiling) {
        if (bottom(a) >= top(b) - st.height_tolerance_m && top(a) > top(b) + st.height_tolerance_m)
          links_.push_back({a.id, Relation::Above, b.id});
        if (top(a) <= bottom(b) + st.height_tolerance_m && bottom(a) < bottom(b) - st.height_tolerance_m)
          links_.push_back({a.id, Relation::Under, b.id});
      }
      if (a.kind == b.kind && (a.kind == EntityKind::Wall || a.kind == EntityKind::Door) &&
          std::abs(a.size_m.z() - b.size_m.z()) <= st.height_tolerance_m)
        links_.push_back({a.id, Relation::EqualHeight, b.id});
    }
  // Available inside: a door in the line of a wall, within its span or at
  // its end; anything standing on the floor within the floor's extent (the building).
  for (const int di : of_kind(EntityKind::Door)) {
    const auto& door = seg_.doors[static_cast<std::size_t>(entity(di).index)];
    for (const int wi : of_kind(EntityKind::Wall)) {
      const auto& w = seg_.walls[static_cast<std::size_t>(entity(wi).index)];
      const Eigen::Vector2d d = w.direction(), n(-d.y(), d.x());
      const double off = std::abs(n.dot(door.center_m - w.from_m)), along = d.dot(door.center_m - w.from_m);
      const double reach = door.width_m / 2 + w.thickness_m + st.inside_margin_m;
      if (off <= w.thickness_m / 2 + st.inside_margin_m && along >= -reach && along <= w.length_m() + reach)
        links_.push_back({di, Relation::Inside, wi});
    }
  }
  // The paper's stairs model: each step above and parallel to the one
  // before it, under the next, all inside their staircase.
  const auto step_ids = of_kind(EntityKind::Step);
  for (std::size_t i = 0; i < step_ids.size(); ++i) {
    links_.push_back({step_ids[i], Relation::Inside, steps[i].stairs_id});
    if (i > 0 && steps[i - 1].stairs_id == steps[i].stairs_id) {
      links_.push_back({step_ids[i], Relation::Above, step_ids[i - 1]});
      links_.push_back({step_ids[i - 1], Relation::Under, step_ids[i]});
    }
  }
  const Entity& floor = entities_.front();
  const Box2 fb = footprint(floor);
  for (const auto& e : entities_) {
    if (e.kind != EntityKind::Stairs && e.kind != EntityKind::Obstacle && e.kind != EntityKind::Wall) continue;
    const Box2 b = footprint(e);
    const double m = st.inside_margin_m + 0.2;
    if (b.lo.x() >= fb.lo.x() - m && b.lo.y() >= fb.lo.y() - m && b.hi.x() <= fb.hi.x() + m && b.hi.y() <= fb.hi.y() + m)
      links_.push_back({e.id, Relation::Inside, floor.id});
  }
}

std::vector<int> SemanticNet::of_kind(EntityKind kind) const {
  std::vector<int> out;
  for (const auto& e : entities_)
    if (e.kind == kind) out.push_back(e.id);
  return out;
}

std::vector<int> SemanticNet::related(int id, Relation relation) const {
  std::vector<int> out;
  for (const auto& l : links_)
    if (l.from == id && l.relation == relation) out.push_back(l.to);
  return out;
}

bool SemanticNet::holds(int from, Relation relation, int to) const {
  return std::any_of(links_.begin(), links_.end(),
                     [&](const Link& l) { return l.from == from && l.relation == relation && l.to == to; });
}

std::string to_json(const SemanticNet& net) {
  const auto& seg = net.segmentation();
  std::ostringstream o;
  o << "{\n  \"floor_height_m\": " << number(seg.floor.height_m) << ",\n";
  o << "  \"ceiling_height_m\": " << (seg.ceiling.found ? number(seg.ceiling.height_m) : "null") << ",\n";
  o << "  \"entities\": [";
  bool first = true;
  for (const auto& e : net.entities()) {
    o << (first ? "\n" : ",\n") << "    {\"id\": " << e.id << ", \"kind\": \"" << to_string(e.kind) << "\", \"name\": \""
      << e.name << "\", \"position_m\": " << vec(e.position_m) << ", \"size_m\": " << vec(e.size_m)
      << ", \"yaw_deg\": " << number(e.yaw_rad * 180.0 / M_PI);
    first = false;
    const auto i = static_cast<std::size_t>(e.index);
    switch (e.kind) {
      case EntityKind::Wall: {
        const auto& w = seg.walls[i];
        o << ", \"from_m\": " << vec(w.from_m) << ", \"to_m\": " << vec(w.to_m) << ", \"height_m\": " << number(w.height_m)
          << ", \"thickness_m\": " << number(w.thickness_m) << ", \"both_faces_seen\": " << (w.both_faces_seen ? "true" : "false")
          << ", \"openings\": [";
        for (std::size_t k = 0; k < w.openings.size(); ++k)
          o << (k ? ", " : "") << "{\"at_m\": " << number(w.openings[k].at_m) << ", \"width_m\": "
            << number(w.openings[k].width_m) << ", \"height_m\": " << number(w.openings[k].height_m) << "}";
        o << "]";
        break;
      }
      case EntityKind::Door: {
        const auto& d = seg.doors[i];
        o << ", \"width_m\": " << number(d.width_m) << ", \"height_m\": " << number(d.height_m)
          << ", \"lintel\": " << (d.lintel ? "true" : "false") << ", \"panel\": " << (d.panel ? "true" : "false");
        break;
      }
      case EntityKind::Stairs: {
        const auto& s = seg.stairs[i];
        o << ", \"start_m\": " << vec(s.start_m) << ", \"steps\": " << s.steps << ", \"riser_m\": " << number(s.riser_m)
          << ", \"tread_m\": " << number(s.tread_m) << ", \"width_m\": " << number(s.width_m)
          << ", \"landing_m\": " << number(s.landing_m);
        break;
      }
      default: break;
    }
    o << "}";
  }
  o << "\n  ],\n  \"relations\": [";
  first = true;
  for (const auto& l : net.links()) {
    o << (first ? "\n" : ",\n") << "    [\"" << net.entity(l.from).name << "\", \"" << to_string(l.relation) << "\", \""
      << net.entity(l.to).name << "\"]";
    first = false;
  }
  o << "\n  ]\n}\n";
  return o.str();
}

}  // namespace rise::semantic
