#pragma once

// The real buildings' truth files (tests/data/buildings/*.json, format and
// evaluation rule in the README there) and the score of a Segmentation's
// walls and doors against one: precision and recall of walls by length, of
// doors by count.

#include <json/json.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "semantic/segmentation.hpp"

namespace rise::semantic::testing {

struct TruthDoor {
  Eigen::Vector2d center_m{0, 0};
  double width_m = 0.0;
};

struct BuildingTruth {
  std::string source, image;   ///< relative to RISE_TEST_DATA; image: ROS maps only
  double resolution_m = 0.05;  ///< CARMEN logs: the grid_from_scans cell size
  std::optional<Eigen::Vector4d> region;  ///< xmin, ymin, xmax, ymax: only this was labelled
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> walls;
  std::vector<TruthDoor> doors;
};

/// Throws std::runtime_error "path: key: ..." for a file that is not a truth file.
inline BuildingTruth read_building_truth(const std::string& path) {
  std::ifstream in(path);
  Json::Value root;
  Json::CharReaderBuilder builder;
  std::string errors;
  if (!in || !Json::parseFromStream(builder, in, &root, &errors))
    throw std::runtime_error(path + ": " + (in ? errors : std::string("cannot read")));
  const auto fail = [&](const std::string& key, const std::string& what) {
    throw std::runtime_error(path + ": " + key + ": " + what);
  };
  const auto number_list = [&](const Json::Value& v, Json::ArrayIndex n, const std::string& key) {
    if (!v.isArray() || v.size() != n) fail(key, "expected " + std::to_string(n) + " numbers");
    std::vector<double> out;
    for (const auto& x : v) {
      if (!x.isNumeric()) fail(key, "not a number");
      out.push_back(x.asDouble());
    }
    return out;
  };
  BuildingTruth t;
  if (!root["source"].isString()) fail("source", "missing");
  t.source = root["source"].asString();
  t.image = root.get("image", "").asString();
  t.resolution_m = root.get("resolution_m", 0.05).asDouble();
  if (root.isMember("region")) {
    const auto r = number_list(root["region"], 4, "region");
    t.region = Eigen::Vector4d(r[0], r[1], r[2], r[3]);
  }
  for (Json::ArrayIndex i = 0; i < root["walls"].size(); ++i) {
    const auto w = number_list(root["walls"][i], 4, "walls[" + std::to_string(i) + "]");
    t.walls.emplace_back(Eigen::Vector2d(w[0], w[1]), Eigen::Vector2d(w[2], w[3]));
  }
  for (Json::ArrayIndex i = 0; i < root["doors"].size(); ++i) {
    const Json::Value& d = root["doors"][i];
    const auto c = number_list(d["center"], 2, "doors[" + std::to_string(i) + "].center");
    if (!d["width"].isNumeric()) fail("doors[" + std::to_string(i) + "].width", "missing");
    t.doors.push_back({{c[0], c[1]}, d["width"].asDouble()});
  }
  return t;
}

struct BuildingScore {
  double wall_precision = 0, wall_recall = 0;  ///< by length
  double detected_wall_m = 0, truth_wall_m = 0;
  int doors_detected = 0, doors_truth = 0, doors_matched = 0;
  double door_precision = 0, door_recall = 0;  ///< 1 where there is nothing to count
};

namespace detail {

using Segment = std::pair<Eigen::Vector2d, Eigen::Vector2d>;

// Liang-Barsky: the part of a..b inside the rectangle, or none.
inline std::optional<Segment> clipped(const Segment& s, const std::optional<Eigen::Vector4d>& region) {
  if (!region) return s;
  const Eigen::Vector2d d = s.second - s.first;
  double t0 = 0, t1 = 1;
  const double p[4] = {-d.x(), d.x(), -d.y(), d.y()};
  const double q[4] = {s.first.x() - (*region)[0], (*region)[2] - s.first.x(), s.first.y() - (*region)[1],
                       (*region)[3] - s.first.y()};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return std::nullopt;
    } else if (p[i] < 0) {
      t0 = std::max(t0, q[i] / p[i]);
    } else {
      t1 = std::min(t1, q[i] / p[i]);
    }
  }
  if (t0 >= t1) return std::nullopt;
  return Segment{s.first + t0 * d, s.first + t1 * d};
}

// Where detected segment `d` matches truth `t` (README: parallel within
// 10°, both ends of the overlapping part within 0.3 m of the truth line):
// the overlap as a parameter range along t (metres from t.first), or none.
inline std::optional<std::pair<double, double>> overlap_on_truth(const Segment& d, const Segment& t) {
  const double len = (t.second - t.first).norm();
  if (len <= 0 || (d.second - d.first).norm() <= 0) return std::nullopt;
  const Eigen::Vector2d u = (t.second - t.first) / len, n(-u.y(), u.x());
  const Eigen::Vector2d v = (d.second - d.first).normalized();
  if (std::abs(u.x() * v.y() - u.y() * v.x()) > std::sin(10.0 * M_PI / 180.0)) return std::nullopt;
  const double s0 = u.dot(d.first - t.first), s1 = u.dot(d.second - t.first);
  const double lo = std::max(std::min(s0, s1), 0.0), hi = std::min(std::max(s0, s1), len);
  if (hi <= lo) return std::nullopt;
  // The detected segment's points over the overlap's ends, and their distance from the truth line.
  for (const double s : {lo, hi}) {
    const double f = (s - s0) / (s1 - s0);
    if (std::abs(n.dot(d.first + f * (d.second - d.first) - t.first)) > 0.3) return std::nullopt;
  }
  return std::make_pair(lo, hi);
}

inline double union_length(std::vector<std::pair<double, double>> r) {
  std::sort(r.begin(), r.end());
  double total = 0, end = -1e300;
  for (const auto& [a, b] : r) {
    if (b <= end) continue;
    total += b - std::max(a, end);
    end = b;
  }
  return total;
}

}  // namespace detail

/// The README's rule. Detected walls are split at their openings (the
/// truth has a wall each side of a doorway).
inline BuildingScore score_building(const Segmentation& seg, const BuildingTruth& truth) {
  using detail::Segment;
  std::vector<Segment> found, expected;
  for (const Wall& w : seg.walls) {
    const Eigen::Vector2d u = w.direction();
    double at = 0;
    for (const Opening& o : w.openings) {
      if (const auto c = detail::clipped({w.from_m + at * u, w.from_m + o.at_m * u}, truth.region)) found.push_back(*c);
      at = o.at_m + o.width_m;
    }
    if (const auto c = detail::clipped({w.from_m + at * u, w.to_m}, truth.region)) found.push_back(*c);
  }
  for (const auto& t : truth.walls)
    if (const auto c = detail::clipped(t, truth.region)) expected.push_back(*c);

  BuildingScore s;
  std::vector<std::vector<std::pair<double, double>>> covered(expected.size());
  double matched_m = 0;
  for (const Segment& d : found) {
    const double len = (d.second - d.first).norm();
    s.detected_wall_m += len;
    std::vector<std::pair<double, double>> own;  // matched parts, along d
    for (std::size_t i = 0; i < expected.size(); ++i) {
      const auto o = detail::overlap_on_truth(d, expected[i]);
      if (!o) continue;
      covered[i].push_back(*o);
      const Eigen::Vector2d u = (expected[i].second - expected[i].first).normalized(), v = (d.second - d.first) / len;
      const double a = v.dot(expected[i].first + o->first * u - d.first), b = v.dot(expected[i].first + o->second * u - d.first);
      own.emplace_back(std::clamp(std::min(a, b), 0.0, len), std::clamp(std::max(a, b), 0.0, len));
    }
    matched_m += detail::union_length(own);
  }
  double covered_m = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    s.truth_wall_m += (expected[i].second - expected[i].first).norm();
    covered_m += detail::union_length(covered[i]);
  }
  s.wall_precision = s.detected_wall_m > 0 ? matched_m / s.detected_wall_m : 1.0;
  s.wall_recall = s.truth_wall_m > 0 ? covered_m / s.truth_wall_m : 1.0;

  const auto inside = [&](const Eigen::Vector2d& p) {
    return !truth.region || (p.x() >= (*truth.region)[0] && p.y() >= (*truth.region)[1] &&
                             p.x() <= (*truth.region)[2] && p.y() <= (*truth.region)[3]);
  };
  std::vector<Door> doors;
  for (const Door& d : seg.doors)
    if (inside(d.center_m)) doors.push_back(d);
  std::vector<TruthDoor> truth_doors;
  for (const TruthDoor& d : truth.doors)
    if (inside(d.center_m)) truth_doors.push_back(d);
  // Nearest pairs first; each door on either side matched once.
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < doors.size(); ++i)
    for (std::size_t j = 0; j < truth_doors.size(); ++j) {
      const double dist = (doors[i].center_m - truth_doors[j].center_m).norm();
      if (dist <= 0.5 && std::abs(doors[i].width_m - truth_doors[j].width_m) <= 0.3) pairs.emplace_back(dist, i, j);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<char> used_found(doors.size(), 0), used_truth(truth_doors.size(), 0);
  for (const auto& [dist, i, j] : pairs)
    if (!used_found[i] && !used_truth[j]) used_found[i] = used_truth[j] = 1, ++s.doors_matched;
  s.doors_detected = static_cast<int>(doors.size());
  s.doors_truth = static_cast<int>(truth_doors.size());
  s.door_precision = s.doors_detected > 0 ? s.doors_matched / static_cast<double>(s.doors_detected) : 1.0;
  s.door_recall = s.doors_truth > 0 ? s.doors_matched / static_cast<double>(s.doors_truth) : 1.0;
  return s;
}

}  // namespace rise::semantic::testing
