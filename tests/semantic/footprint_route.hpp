#pragma once

// Driving the tracked robot from one place of a generated world to another
// as an operator would, for the tests that check a world rise-semantic wrote
// can be driven: a route planned for the robot's footprint over the map the
// world was made from (A* over poses every 10 cm and 32 headings, moves
// straight ahead or back, turns on the spot and, where a turn is blocked,
// side steps; the footprint clear of every cell that is not free or that
// a world box reaches into, at every pose and halfway through every move),
// then driven with the stick: turn on the spot, drive straight (on or
// back) to the run's end, turn, and so on.

#include <Eigen/Core>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <vector>

#include "semantic/occupancy_grid.hpp"
#include "sim/simulation.hpp"
#include "tests/semantic/sim_drive.hpp"

namespace rise::semantic::testing {

// The 32 headings: the directions of these lattice steps (0°, 18.4°, 26.6°, 33.7°, 45°, ...).
inline const std::array<Eigen::Vector2i, 32> kSteps = {
    {{1, 0}, {3, 1}, {2, 1}, {3, 2}, {1, 1}, {2, 3}, {1, 2}, {1, 3}, {0, 1}, {-1, 3}, {-1, 2}, {-2, 3}, {-1, 1}, {-3, 2}, {-2, 1}, {-3, 1},
     {-1, 0}, {-3, -1}, {-2, -1}, {-3, -2}, {-1, -1}, {-2, -3}, {-1, -2}, {-1, -3}, {0, -1}, {1, -3}, {1, -2}, {2, -3}, {1, -1}, {3, -2}, {2, -1}, {3, -1}}};
constexpr int kHeadings = 32;
constexpr int kStride = 2;  // lattice points every kStride cells (10 cm)

/// One run of a route: turn on the spot to `yaw_rad`, then straight to
/// `end`, ahead or (`backward`) back.
struct Leg {
  double yaw_rad = 0;
  Eigen::Vector2d end;
  bool backward = false;
};

class FootprintRoutes {
 public:
  /// `open`: 255 where the map's cell is free and outside the world's boxes
  /// (CV_8U, the grid's rows and columns); the footprint reaches `front_m`
  /// ahead of the robot's base and `rear_m` behind it, `width_m` wide.
  FootprintRoutes(const OccupancyGrid& g, const cv::Mat& open, double front_m, double rear_m, double width_m)
      : g_(g), open_(open), front_m_(front_m), rear_m_(rear_m), width_m_(width_m), cols_((g.width + kStride - 1) / kStride), rows_((g.height + kStride - 1) / kStride),
        valid_(static_cast<std::size_t>(cols_) * rows_ * kHeadings, -1), moves_(valid_.size(), 0) {
    cv::distanceTransform(open, clear_, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  }

  /// The legs from the pose (`from`, `from_yaw_rad`) to one before the
  /// doorway whose middle is `door`, facing it along unit `toward` within
  /// 10° (the headings lie up to 18.4° apart; the last turn on the spot to
  /// `toward` must be clear too): on the line through its middle, 0.9-1.6 m
  /// before it, within 7 cm of that line. Empty when there is no way.
  std::vector<Leg> route(const Eigen::Vector2d& from, double from_yaw_rad, const Eigen::Vector2d& door,
                         const Eigen::Vector2d& toward) const {
    const Eigen::Vector2d far_end = door - 1.6 * toward;
    const auto to_goal = [&](const Eigen::Vector2d& p) {  // from the goal's segment: A*'s estimate
      const double t = std::clamp((p - far_end).dot(toward) / 0.7, 0.0, 1.0);
      return (p - (far_end + t * 0.7 * toward)).norm();
    };
    const auto goal = [&](std::size_t i) {
      const Eigen::Vector2d q = position(i) - door;
      const Eigen::Vector2d h = heading(static_cast<int>(i % kHeadings));
      return -toward.dot(q) >= 0.9 && -toward.dot(q) <= 1.6 && std::abs(toward.x() * q.y() - toward.y() * q.x()) <= 0.07 &&
             h.dot(toward) >= std::cos(10 * M_PI / 180) && fits(position(i), (h + toward).normalized()) &&
             fits(position(i), toward);
    };
    const Eigen::Vector2i s = lattice_of(from);
    const std::size_t start = index(s.x(), s.y(), nearest_heading(from_yaw_rad));
    if (!inside(s) || !valid(start)) return {};
    std::vector<float> cost(valid_.size(), std::numeric_limits<float>::infinity());
    std::vector<std::int32_t> parent(valid_.size(), -1);
    using Item = std::pair<double, std::size_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
    cost[start] = 0;
    open.emplace(to_goal(position(start)), start);
    while (!open.empty()) {
      const auto [f, i] = open.top();
      open.pop();
      const double c = cost[i];
      if (f > c + to_goal(position(i)) + 1e-3) continue;  // stale (costs are floats)
      if (goal(i)) return legs(i, parent);
      const auto relax = [&](std::size_t n, double step) {
        if (c + step >= cost[n]) return;
        cost[n] = static_cast<float>(c + step), parent[n] = static_cast<std::int32_t>(i);
        open.emplace(c + step + to_goal(position(n)), n);
      };
      const std::uint16_t can = moves(i);
      for (int m = 0; m < kMoves; ++m) {
        if (!(can & (1u << m))) continue;
        const std::size_t n = target(i, m);
        if (m < 2) {  // a turn on the spot
          relax(n, 0.15);
          continue;
        }
        // Each metre costs more near things: the route keeps to the middle.
        const Eigen::Vector2d mid = (position(i) + position(n)) / 2;
        const double near = 0.6 / std::max(clearance(mid), 0.05);
        const double metres = (position(n) - position(i)).norm() * (1 + near * near * near * near);
        if (m < 4)
          relax(n, (m == 2 ? 1 : 2) * metres);  // ahead, or back at twice the cost (an operator backs up where he must)
        else
          relax(n, metres + 0.3);  // a side step and its two small turns
      }
    }
    return {};
  }

 private:
  // The moves from a pose: 0, 1 a turn on the spot to the next heading
  // right or left, clear halfway round too; 2, 3 a lattice step ahead or
  // back, clear halfway; 4-9 a side step, as an operator edges over in a
  // corridor too narrow to turn in: turn a little (atan(1 / kAhead): 7-18°),
  // drive on kAhead steps and one step aside, turn back, clear at the
  // slant every 5 cm along the way and halfway through each turn.
  static constexpr int kMoves = 10;
  static constexpr std::array<int, 3> kAhead = {3, 5, 8};

  // The pose move `m` from pose `i` ends at, if inside the lattice, else `i`.
  std::size_t target(std::size_t i, int m) const {
    const int x = static_cast<int>(i / kHeadings % cols_), y = static_cast<int>(i / kHeadings / cols_), k = static_cast<int>(i % kHeadings);
    if (m < 2) return index(x, y, (k + (m == 0 ? -1 : 1) + kHeadings) % kHeadings);
    Eigen::Vector2i to(x, y);
    if (m < 4)
      to += (m == 2 ? 1 : -1) * kSteps[k];
    else
      to += kAhead[(m - 4) / 2] * kSteps[k] + ((m - 4) % 2 == 0 ? -1 : 1) * kSteps[(k + kHeadings / 4) % kHeadings];
    return inside(to) ? index(to.x(), to.y(), k) : i;
  }

  // Which moves from pose `i` (bit m for move m) are clear: worked out once.
  std::uint16_t moves(std::size_t i) const {
    if (moves_[i] & kKnown) return moves_[i];
    std::uint16_t can = kKnown;
    const Eigen::Vector2d from = position(i), h = heading(static_cast<int>(i % kHeadings));
    for (int m = 0; m < kMoves; ++m) {
      if (m == 4 && (can & 3u) == 3u) break;  // side steps only where a turn is blocked
      const std::size_t n = target(i, m);
      if (n == i || !valid(n)) continue;
      const Eigen::Vector2d to = position(n);
      bool clear;
      if (m < 2) {
        clear = fits(from, (h + heading(static_cast<int>(n % kHeadings))).normalized());
      } else if (m < 4) {
        clear = fits((from + to) / 2, h);
      } else {
        const Eigen::Vector2d u = (to - from).normalized(), half_turn = (u + h).normalized();
        clear = fits(from, half_turn) && fits(to, half_turn);
        const int samples = static_cast<int>(std::ceil((to - from).norm() / 0.05));
        for (int t = 0; t <= samples && clear; ++t) clear = fits(from + (to - from) * t / samples, u);
      }
      if (clear) can = static_cast<std::uint16_t>(can | (1u << m));
    }
    return moves_[i] = can;
  }

  Eigen::Vector2i lattice_of(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d c = ((p - g_.origin_m) / g_.resolution_m - Eigen::Vector2d(0.5, 0.5)) / kStride;
    return {static_cast<int>(std::lround(c.x())), static_cast<int>(std::lround(c.y()))};
  }
  bool inside(const Eigen::Vector2i& c) const { return c.x() >= 0 && c.y() >= 0 && c.x() < cols_ && c.y() < rows_; }
  std::size_t index(int x, int y, int k) const { return (static_cast<std::size_t>(y) * cols_ + x) * kHeadings + k; }
  Eigen::Vector2d position(std::size_t i) const {
    return g_.center(static_cast<int>(i / kHeadings % cols_) * kStride, static_cast<int>(i / kHeadings / cols_) * kStride);
  }
  static Eigen::Vector2d heading(int k) { return kSteps[k].cast<double>().normalized(); }
  static int nearest_heading(double yaw) {
    int best = 0;
    for (int k = 0; k < kHeadings; ++k)
      if (std::abs(std::remainder(yaw - std::atan2(kSteps[k].y(), kSteps[k].x()), 2 * M_PI)) <
          std::abs(std::remainder(yaw - std::atan2(kSteps[best].y(), kSteps[best].x()), 2 * M_PI)))
        best = k;
    return best;
  }

  // Metres from `p` to the nearest cell that is not open, at least (the
  // transform is from cell centre to cell centre).
  double clearance(const Eigen::Vector2d& p) const {
    const Eigen::Vector2i c = g_.cell_of(p);
    if (!g_.contains(c.x(), c.y())) return 0;
    return std::max(0.0, clear_.at<float>(c.y(), c.x()) * g_.resolution_m - (p - g_.center(c.x(), c.y())).norm() -
                             g_.resolution_m / 2);
  }

  // The footprint at `p` heading along `h` over open cells only: at once
  // where its corners are nearer than the nearest closed cell, ...
  // else every 2.5 cm over it.
  bool fits(const Eigen::Vector2d& p, const Eigen::Vector2d& h) const {
    if (clearance(p) >= std::hypot(std::max(front_m_, rear_m_), width_m_ / 2)) return true;
    const double length = front_m_ + rear_m_;
    // ... or where five discs along it, which cover it, are each clear ...
    const double half = length / 10, radius = std::hypot(half, width_m_ / 2);
    bool discs = true;
    for (int k = 0; k < 5 && discs; ++k) discs = clearance(p + ((2 * k + 1) * half - rear_m_) * h) >= radius;
    if (discs) return true;
    // (along each of its lines, a point's clearance is skipped over at once).
    const Eigen::Vector2d side(-h.y(), h.x());
    const int nu = static_cast<int>(std::ceil(length / 0.025)), nv = static_cast<int>(std::ceil(width_m_ / 0.025));
    for (int b = 0; b <= nv; ++b) {
      const Eigen::Vector2d line = p - rear_m_ * h + (b * width_m_ / nv - width_m_ / 2) * side;
      for (int a = 0; a <= nu;) {
        const Eigen::Vector2d q = line + a * length / nu * h;
        const Eigen::Vector2i c = g_.cell_of(q);
        if (!g_.contains(c.x(), c.y()) || open_.at<uint8_t>(c.y(), c.x()) == 0) return false;
        // (less a fifth of a cell: the nearest cell centre may lie that much nearer than its corner)
        a += std::max(1, static_cast<int>((clearance(q) - g_.resolution_m / 5) / (length / nu)));
      }
    }
    return true;
  }

  bool valid(std::size_t i) const {
    if (valid_[i] < 0) valid_[i] = fits(position(i), heading(static_cast<int>(i % kHeadings))) ? 1 : 0;
    return valid_[i] == 1;
  }

  std::vector<Leg> legs(std::size_t goal, const std::vector<std::int32_t>& parent) const {
    std::vector<std::size_t> poses;
    for (auto i = static_cast<std::int32_t>(goal); i >= 0; i = parent[static_cast<std::size_t>(i)])
      poses.push_back(static_cast<std::size_t>(i));
    std::reverse(poses.begin(), poses.end());
    std::vector<Leg> out;
    bool moved = false;  // the last leg has run, not only turned
    for (std::size_t j = 0; j < poses.size(); ++j) {
      const Eigen::Vector2d h = heading(static_cast<int>(poses[j] % kHeadings)), p = position(poses[j]);
      const double yaw = std::atan2(h.y(), h.x());
      const Eigen::Vector2d u = j > 0 ? Eigen::Vector2d(p - position(poses[j - 1])) : Eigen::Vector2d::Zero();
      if (std::abs(h.x() * u.y() - h.y() * u.x()) > 1e-6) {  // a side step (off the heading): one run at its slant
        out.push_back({std::atan2(u.y(), u.x()), p});
        moved = true;
        continue;
      }
      if (out.empty() || std::abs(std::remainder(out.back().yaw_rad - yaw, 2 * M_PI)) > 1e-9) {
        out.push_back({yaw, p});  // a turn on the spot
        moved = false;
        continue;
      }
      const bool backward = h.dot(p - out.back().end) < 0;
      if (moved && backward != out.back().backward) out.push_back({yaw, p, backward});  // the other way
      out.back().end = p, out.back().backward = backward, moved = true;
    }
    return out;
  }

  const OccupancyGrid& g_;
  cv::Mat open_, clear_;
  double front_m_, rear_m_, width_m_;
  int cols_, rows_;
  mutable std::vector<std::int8_t> valid_;  ///< per pose: -1 not yet known
  static constexpr std::uint16_t kKnown = 1u << 15;
  mutable std::vector<std::uint16_t> moves_;  ///< per pose: its clear moves, once kKnown
};

inline Eigen::Vector2d base_of(const rise::sim::Simulation& sim) {
  return {sim.snapshot().position_m[0], sim.snapshot().position_m[1]};
}

// The stick for `forward` and a turn of `error` rad to the left (right on the stick turns right).
inline rise::sim::ControlInput steered(float forward, double error, int speed) {
  rise::sim::ControlInput in = drive(forward, speed);
  in.axes["drive_x"] = static_cast<float>(std::clamp(-2.0 * error, -1.0, 1.0));
  return in;
}

/// Turns the robot on the spot to `yaw_rad`; false when it did not get there in 10 s.
inline bool face(rise::sim::Simulation& sim, double yaw_rad, std::vector<rise::sim::SimEvent>& log) {
  const auto error = [&] { return std::remainder(yaw_rad - sim.snapshot().yaw_rad(), 2 * M_PI); };
  for (double t = 0; t < 10.0; t += 0.02) {
    if (std::abs(error()) < 0.02) {
      sim.set_input(drive(0.0f, 1));
      run(sim, 0.2, log);
      return true;
    }
    const double e = error();
    sim.set_input(steered(0.0f, std::copysign(std::max(std::abs(e), 0.15), e), 1));
    run(sim, 0.02, log);
  }
  return false;
}

/// Drives the robot straight to `end`, ahead or (`backward`) back, steering
/// at it, until it is past it (within 2 cm along the way); false when it
/// made no headway for 3 s.
inline bool drive_to(rise::sim::Simulation& sim, const Eigen::Vector2d& end, std::vector<rise::sim::SimEvent>& log,
                     bool backward = false) {
  const Eigen::Vector2d way = (end - base_of(sim)).normalized();
  const double sign = backward ? -1.0 : 1.0;
  Eigen::Vector2d was = base_of(sim);
  double still_s = 0;
  while (way.dot(end - base_of(sim)) > 0.02) {
    const Eigen::Vector2d to_end = end - base_of(sim);
    const Eigen::Vector2d aim = sign * (to_end.norm() > 0.3 ? to_end : way);  // where the robot should face
    const double error = std::remainder(std::atan2(aim.y(), aim.x()) - sim.snapshot().yaw_rad(), 2 * M_PI);
    const double speed = std::clamp(0.15 + 0.6 * way.dot(to_end), 0.0, 1.0);
    sim.set_input(steered(static_cast<float>(sign * speed), error, 2));
    run(sim, 0.02, log);
    still_s = (base_of(sim) - was).norm() > 0.02 ? 0 : still_s + 0.02;
    if ((base_of(sim) - was).norm() > 0.02) was = base_of(sim);
    if (still_s > 3.0) return false;
  }
  sim.set_input(drive(0.0f, 1));
  run(sim, 0.2, log);
  return true;
}

/// Drives `legs` (turn, then straight on or back); false where a turn or a
/// run did not end. A run shorter than 0.3 m goes straight on or back to
/// where its end lies across the robot's way: the first run's end is the
/// route's lattice pose, up to 7 cm from where the robot stands and to any
/// side of it; steering at it would drive a loop.
inline bool drive_legs(rise::sim::Simulation& sim, const std::vector<Leg>& legs, std::vector<rise::sim::SimEvent>& log) {
  for (const Leg& leg : legs) {
    if (!face(sim, leg.yaw_rad, log)) return false;
    Eigen::Vector2d end = leg.end;
    bool backward = leg.backward;
    const Eigen::Vector2d to_end = end - base_of(sim);
    if (to_end.norm() < 0.3) {
      const double yaw = sim.snapshot().yaw_rad();
      const Eigen::Vector2d h(std::cos(yaw), std::sin(yaw));
      end = base_of(sim) + h.dot(to_end) * h;
      backward = h.dot(to_end) < 0;
    }
    if ((end - base_of(sim)).norm() > 0.02 && !drive_to(sim, end, log, backward)) return false;
  }
  return true;
}

}  // namespace rise::semantic::testing
