#include "semantic/pose_graph_io.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include "semantic/cloud_formats.hpp"

namespace rise::semantic {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using formats::fail_line;

struct EdgeLine {
  long long from = 0, to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  Matrix6d information = Matrix6d::Identity();
  std::size_t line = 0;
  std::string tag;
};

// One line's values after the tag, each checked to be a finite number.
std::vector<double> values(const std::vector<std::string_view>& w, std::size_t first, const std::string& path,
                           std::size_t line, const std::string& tag) {
  std::vector<double> v;
  for (std::size_t i = first; i < w.size(); ++i) {
    v.push_back(formats::number<double>(w[i], path, line, tag));
    if (!std::isfinite(v.back())) fail_line(path, line, tag + ": value " + std::to_string(i) + " is not finite");
  }
  return v;
}

long long id(std::string_view word, const std::string& path, std::size_t line, const std::string& tag) {
  return formats::number<long long>(word, path, line, tag + ": vertex id");
}

// g2o's information: the upper triangle row by row (readInformationMatrix).
Matrix6d upper_triangle(const double* v) {
  Matrix6d m;
  for (int i = 0, k = 0; i < 6; ++i) {
    for (int j = i; j < 6; ++j, ++k) m(i, j) = m(j, i) = v[k];
  }
  return m;
}

Eigen::Isometry3d from_quaternion(const double* v, const std::string& path, std::size_t line, const std::string& tag) {
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    fail_line(path, line, tag + ": quaternion norm " + std::to_string(q.norm()) + " is not 1");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

Eigen::Isometry3d from_planar(double x, double y, double theta) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T;
}

// TORO's EDGE3/VERTEX3 angles: R = Rz(yaw)·Ry(pitch)·Rx(roll).
Eigen::Isometry3d from_euler(const double* v) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

// g2o's EdgeSE3 error is (t, q.xyz) of the error pose (toVectorMQT, w ≥ 0),
// and q.xyz = sin(θ/2)·axis ≈ ½·(rotation vector): with D = diag(1,1,1,½,½,½)
// its rᵀ·Ω·r is ours with D·Ω·D.
Matrix6d from_quaternion_information(const Matrix6d& omega) {
  Eigen::Matrix<double, 6, 1> d;
  d << 1, 1, 1, 0.5, 0.5, 0.5;
  return d.asDiagonal() * omega * d.asDiagonal();
}

// EDGE_SE2's I11 I12 I13 I22 I23 I33 over (x, y, θ) in our (x y z rx ry rz).
Matrix6d from_planar_information(const double* v) {
  Matrix6d m = Matrix6d::Zero();
  const int index[3] = {0, 1, 5};
  for (int i = 0, k = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j, ++k) m(index[i], index[j]) = m(index[j], index[i]) = v[k];
  }
  const double stiff = kPlanarStiffness * std::max({v[0], v[3], v[5]});
  m(2, 2) = m(3, 3) = m(4, 4) = stiff;
  return m;
}

void check_positive_definite(const Matrix6d& m, const std::string& path, std::size_t line, const std::string& tag) {
  if (Eigen::LLT<Matrix6d>(m).info() != Eigen::Success) {
    fail_line(path, line, tag + ": information matrix is not positive definite");
  }
}

// One line of the file: its words, tag and number.
struct GraphLine {
  const std::string& path;
  const std::vector<std::string_view>& w;
  std::string tag;
  std::size_t n;

  void expect(std::size_t count, const char* what) const {
    if (w.size() != count + 1) {
      fail_line(path, n, tag + ": " + std::to_string(w.size() - 1) + " values, expected " + std::to_string(count) +
                             " (" + what + ")");
    }
  }
};

// An EDGE_SE3:QUAT, EDGE_SE2 or EDGE3 line; EDGE_SE2 marks the graph planar.
EdgeLine edge_line(const GraphLine& l, bool& planar) {
  const std::string& path = l.path;
  const std::string& tag = l.tag;
  const std::size_t n = l.n;
  EdgeLine e;
  e.line = n;
  e.tag = tag;
  if (tag == "EDGE_SE3:QUAT") {
    l.expect(30, "i j x y z qx qy qz qw and 21 information values");
  } else if (tag == "EDGE_SE2") {
    l.expect(11, "i j x y theta and 6 information values");
  } else {
    l.expect(29, "i j x y z roll pitch yaw and 21 information values");
  }
  e.from = id(l.w[1], path, n, tag);
  e.to = id(l.w[2], path, n, tag);
  if (e.from == e.to) fail_line(path, n, tag + ": an edge from vertex " + std::to_string(e.from) + " to itself");
  const auto v = values(l.w, 3, path, n, tag);
  if (tag == "EDGE_SE3:QUAT") {
    e.T_from_to = from_quaternion(v.data(), path, n, tag);
    e.information = from_quaternion_information(upper_triangle(v.data() + 7));
  } else if (tag == "EDGE_SE2") {
    e.T_from_to = from_planar(v[0], v[1], v[2]);
    e.information = from_planar_information(v.data() + 3);
    planar = true;
  } else {
    e.T_from_to = from_euler(v.data());
    e.information = upper_triangle(v.data() + 6);
  }
  check_positive_definite(e.information, path, n, tag);
  return e;
}

// The file as its lines give it: vertices (in file order) in `f`, the
// edges and FIX lines kept until every vertex is known (an edge may come
// before its vertices, or a file give no vertices at all).
struct GraphLines {
  explicit GraphLines(const std::string& file) : path(file) {}

  const std::string& path;
  PoseGraphFile f;
  std::unordered_map<long long, std::size_t> node_of;  // vertex id -> node
  std::unordered_map<long long, std::size_t> vertex_line;
  std::vector<EdgeLine> edges;
  std::vector<std::pair<long long, std::size_t>> fix;  // id, line
  std::map<std::string, std::size_t> ignored;

  void read(const GraphLine& l) {
    const std::string& tag = l.tag;
    const std::size_t n = l.n;
    const auto& w = l.w;
    if (tag == "VERTEX_SE3:QUAT") {
      l.expect(8, "id x y z qx qy qz qw");
      const auto v = values(w, 2, path, n, tag);
      add_vertex(l, id(w[1], path, n, tag), from_quaternion(v.data(), path, n, tag));
    } else if (tag == "VERTEX_SE2") {
      l.expect(4, "id x y theta");
      const auto v = values(w, 2, path, n, tag);
      add_vertex(l, id(w[1], path, n, tag), from_planar(v[0], v[1], v[2]));
      f.planar = true;
    } else if (tag == "VERTEX3") {
      l.expect(7, "id x y z roll pitch yaw");
      const auto v = values(w, 2, path, n, tag);
      add_vertex(l, id(w[1], path, n, tag), from_euler(v.data()));
    } else if (tag == "EDGE_SE3:QUAT" || tag == "EDGE_SE2" || tag == "EDGE3") {
      edges.push_back(edge_line(l, f.planar));
    } else if (tag == "FIX") {
      if (w.size() < 2) fail_line(path, n, tag + ": no vertex id");
      for (std::size_t i = 1; i < w.size(); ++i) fix.emplace_back(id(w[i], path, n, tag), n);
    } else {
      ++ignored[tag];
    }
  }

  void add_vertex(const GraphLine& l, long long vertex, const Eigen::Isometry3d& T) {
    if (const auto it = vertex_line.find(vertex); it != vertex_line.end()) {
      fail_line(path, l.n, l.tag + ": vertex " + std::to_string(vertex) + " given twice (first on line " +
                               std::to_string(it->second) + ")");
    }
    vertex_line[vertex] = l.n;
    node_of[vertex] = f.ids.size();
    f.ids.push_back(vertex);
    f.graph.T_world_node.push_back(T);
  }

  // No VERTEX lines: the nodes are the edges' vertices, and the guess is
  // pose(i+1) = pose(i)·T_i,i+1 from the smallest id, using the first
  // i -> i+1 edge of each i.
  void place_by_odometry() {
    for (const auto& e : edges) {
      for (const long long v : {e.from, e.to}) {
        if (node_of.emplace(v, f.ids.size()).second) f.ids.push_back(v);
      }
    }
    std::unordered_map<long long, const EdgeLine*> odometry;
    for (const auto& e : edges) {
      if (e.to == e.from + 1) odometry.emplace(e.from, &e);
    }
    std::vector<bool> placed(f.ids.size(), false);
    f.graph.T_world_node.assign(f.ids.size(), Eigen::Isometry3d::Identity());
    const long long first = *std::min_element(f.ids.begin(), f.ids.end());
    placed[node_of.at(first)] = true;
    for (long long i = first;; ++i) {
      const auto it = odometry.find(i);
      if (it == odometry.end()) break;
      const std::size_t a = node_of.at(i), b = node_of.at(i + 1);
      f.graph.T_world_node[b] = f.graph.T_world_node[a] * it->second->T_from_to;
      placed[b] = true;
    }
    for (std::size_t k = 0; k < placed.size(); ++k) {
      if (!placed[k]) {
        throw std::runtime_error(path + ": vertex " + std::to_string(f.ids[k]) +
                                 ": the file has no VERTEX lines and no chain of i -> i+1 edges from vertex " +
                                 std::to_string(first) + " reaches it");
      }
    }
  }

  // The edges and FIX lines on the nodes.
  void connect() {
    f.graph.edges.reserve(edges.size());
    for (const auto& e : edges) {
      const auto a = node_of.find(e.from), b = node_of.find(e.to);
      if (a == node_of.end() || b == node_of.end()) {
        fail_line(path, e.line, e.tag + ": unknown vertex " + std::to_string(a == node_of.end() ? e.from : e.to));
      }
      f.graph.edges.push_back({a->second, b->second, e.T_from_to, e.information});
      if (e.to != e.from + 1) ++f.loop_closures;
    }
    for (const auto& [vertex, n] : fix) {
      const auto it = node_of.find(vertex);
      if (it == node_of.end()) fail_line(path, n, "FIX: unknown vertex " + std::to_string(vertex));
      f.fixed.push_back(it->second);
    }
  }
};

}  // namespace

PoseGraphFile read_pose_graph(const std::string& path) {
  const std::string text = formats::read_file(path);
  GraphLines g(path);
  formats::Lines lines{text};
  std::string_view line;
  while (lines.next(line)) {
    const auto w = formats::words(line);
    if (w.empty() || w[0].front() == '#') continue;
    g.read(GraphLine{path, w, std::string(w[0]), lines.number});
  }
  g.f.ignored.assign(g.ignored.begin(), g.ignored.end());
  if (g.edges.empty()) throw std::runtime_error(path + ": no edges (EDGE_SE3:QUAT, EDGE_SE2 or EDGE3 lines)");
  g.f.chained = g.f.ids.empty();
  if (g.f.chained) g.place_by_odometry();
  g.connect();
  return std::move(g.f);
}

}  // namespace rise::semantic
