#include "semantic/slam.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <utility>

namespace rise::semantic {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void check_settings(const SlamSettings& s) {
  const auto bad = [](const std::string& what) { throw std::invalid_argument("slam settings: " + what); };
  if (s.scan_voxel_m < 0) bad("scan_voxel_m must be >= 0");
  if (s.map_voxel_m < 0) bad("map_voxel_m must be >= 0");
  if (s.map_scans < 1) bad("map_scans must be >= 1");
  if (s.loop_radius_m < 0) bad("loop_radius_m must be >= 0");
  if (s.loop_min_separation < 1) bad("loop_min_separation must be >= 1");
  if (s.loop_max_per_scan < 0) bad("loop_max_per_scan must be >= 0");
  if (!(s.loop_max_rmse_m > 0)) bad("loop_max_rmse_m must be > 0");
  if (s.loop_min_inlier_ratio < 0 || s.loop_min_inlier_ratio > 1) bad("loop_min_inlier_ratio must be in 0..1");
  if (s.match_min_inlier_ratio < 0 || s.match_min_inlier_ratio > 1) bad("match_min_inlier_ratio must be in 0..1");
  if (!(s.information_sigma_min_m > 0)) bad("information_sigma_min_m must be > 0");
  if (s.relaxation_rounds < 1) bad("relaxation_rounds must be >= 1");
  if (!(s.refine_correspondence_m >= 0)) bad("refine_correspondence_m must be >= 0");
  if (s.source_voxel_m < 0) bad("source_voxel_m must be >= 0");
  if (s.icp.metric == IcpMetric::PointToPlane && s.normals_k < 3) bad("normals_k must be >= 3 for point-to-plane");
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The scans scan i is matched onto, merged in the world frame at their
// current poses: the last k (i-k .. i-1), or i-1 and the k-1 earlier scans
// nearest to where scan i is expected.
Cloud local_map(const std::vector<Cloud>& clouds, const std::vector<Eigen::Isometry3d>& T_world_scan, std::size_t i,
                const Eigen::Vector3d& expected_m, const SlamSettings& s) {
  const auto k = static_cast<std::size_t>(s.map_scans);
  std::vector<std::size_t> chosen;
  if (s.target == SlamTarget::LastScans) {
    for (std::size_t j = i > k ? i - k : 0; j < i; ++j) chosen.push_back(j);
  } else {
    std::vector<std::pair<double, std::size_t>> by_distance;
    for (std::size_t j = 0; j + 1 < i; ++j) {
      by_distance.emplace_back((T_world_scan[j].translation() - expected_m).norm(), j);
    }
    std::sort(by_distance.begin(), by_distance.end());
    chosen.push_back(i - 1);
    for (std::size_t m = 0; m < by_distance.size() && chosen.size() < k; ++m) chosen.push_back(by_distance[m].second);
  }
  Cloud map;
  for (const std::size_t j : chosen) {
    Cloud part = transformed(clouds[j], T_world_scan[j]);
    map.points.insert(map.points.end(), part.points.begin(), part.points.end());
    map.normals.insert(map.normals.end(), part.normals.begin(), part.normals.end());
  }
  return map;
}

// Scan i with its neighbours in the sequence (i-1, i+1), in scan i's frame:
// the target a loop match is checked on; one scan alone is sparse far from
// its sensor.
Cloud neighbourhood(const std::vector<Cloud>& clouds, const std::vector<Eigen::Isometry3d>& T_world_scan,
                    std::size_t i) {
  Cloud map;
  const std::size_t first = i > 0 ? i - 1 : 0, last = std::min(i + 1, clouds.size() - 1);
  for (std::size_t j = first; j <= last; ++j) {
    Cloud part = transformed(clouds[j], T_world_scan[i].inverse() * T_world_scan[j]);
    map.points.insert(map.points.end(), part.points.begin(), part.points.end());
    map.normals.insert(map.normals.end(), part.normals.begin(), part.normals.end());
  }
  return map;
}

// Converged, or at the iteration limit but moving less than a tenth of the
// final pairing distance per step (sliding slowly along a weak direction,
// as ground-dominated scenes do, not lost).
bool settled(const IcpResult& r, const IcpSettings& s) {
  return r.converged || r.last_step_m < 0.1 * s.min_correspondence_m;
}

class Pipeline {
 public:
  Pipeline(const SlamSettings& settings, const SlamProgress& progress) : s_(settings), progress_(progress) {}

  void report(std::size_t done, std::size_t total, std::string_view stage) const {
    if (progress_) progress_(done, total, stage);
  }

  // Scan i onto the merged scans before it. With `chain` (the first round)
  // from the pose the odometry's relative motion predicts, and the match
  // becomes scan i's pose; later rounds match from the relaxed poses and
  // leave them as they are (the match only renews the edge: re-chaining
  // would pile the drift up again).
  std::vector<IcpResult> sequential(const std::vector<Cloud>& clouds, const std::vector<Cloud>& sources,
                                    const std::vector<Eigen::Isometry3d>& odometry,
                                    std::vector<Eigen::Isometry3d>& T_world_scan, bool chain,
                                    std::vector<std::size_t>& refused) const {
    const std::size_t n = clouds.size();
    std::vector<IcpResult> results(n);
    IcpSettings icp_settings = s_.icp;
    if (!chain && s_.refine_correspondence_m > 0) {
      icp_settings.max_correspondence_m =
          std::min(s_.icp.max_correspondence_m, std::max(s_.refine_correspondence_m, s_.icp.min_correspondence_m));
    }
    report(0, n - 1, "sequential icp");
    for (std::size_t i = 1; i < n; ++i) {
      const Eigen::Isometry3d guess =
          chain ? T_world_scan[i - 1] * odometry[i - 1].inverse() * odometry[i] : T_world_scan[i];
      const Cloud target = local_map(clouds, T_world_scan, i, guess.translation(), s_);
      results[i] = icp(sources[i], target, guess, icp_settings);
      if (!results[i].converged && results[i].inlier_ratio >= s_.match_min_inlier_ratio) {
        // Still sliding along a weak direction when the iterations ran out:
        // as many again at the final pairing distance before judging it.
        IcpSettings more = icp_settings;
        more.max_correspondence_m = more.min_correspondence_m;
        const IcpResult first = results[i];
        results[i] = icp(sources[i], target, first.T_target_source, more);
        results[i].iterations += first.iterations;
      }
      if (chain) {
        // A match that did not settle, or that paired almost nothing, is
        // not built on: the scan stays where the odometry put it, and the
        // result says so (refused).
        if (!settled(results[i], icp_settings) || results[i].inlier_ratio < s_.match_min_inlier_ratio) {
          refused.push_back(i);
          results[i].T_target_source = guess;
        }
        T_world_scan[i] = results[i].T_target_source;
      }
      report(i, n - 1, "sequential icp");
    }
    return results;
  }

  // Pairs far apart in the sequence whose centres are close, nearest first,
  // matched pairwise; kept when the match is good.
  std::vector<SlamLoop> loops(const std::vector<Cloud>& clouds, const std::vector<Cloud>& sources,
                              const std::vector<Eigen::Isometry3d>& T_world_scan,
                              int& candidates) const {
    const std::size_t n = clouds.size();
    const auto separation = static_cast<std::size_t>(s_.loop_min_separation);
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t j = 0; j < n; ++j) {
      std::vector<std::pair<double, std::size_t>> near;
      for (std::size_t i = 0; i + separation <= j; ++i) {
        const double d = (T_world_scan[i].translation() - T_world_scan[j].translation()).norm();
        if (d <= s_.loop_radius_m) near.emplace_back(d, i);
      }
      std::sort(near.begin(), near.end());
      const std::size_t keep = std::min(near.size(), static_cast<std::size_t>(s_.loop_max_per_scan));
      for (std::size_t k = 0; k < keep; ++k) pairs.emplace_back(near[k].second, j);
    }
    candidates = static_cast<int>(pairs.size());
    std::vector<SlamLoop> found;
    report(0, pairs.size(), "loop closing");
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto [i, j] = pairs[k];
      const IcpResult r =
          icp(sources[j], neighbourhood(clouds, T_world_scan, i), T_world_scan[i].inverse() * T_world_scan[j], s_.icp);
      if (r.rmse_m <= s_.loop_max_rmse_m && r.inlier_ratio >= s_.loop_min_inlier_ratio) {
        found.push_back({i, j, r.T_target_source, r.rmse_m, r.inlier_ratio});
      }
      report(k + 1, pairs.size(), "loop closing");
    }
    return found;
  }

  PoseGraph graph(const std::vector<Cloud>& sources, const std::vector<Eigen::Isometry3d>& T_world_scan,
                  const std::vector<IcpResult>& sequential, const std::vector<SlamLoop>& loops) const {
    PoseGraph g;
    g.T_world_node = T_world_scan;
    for (std::size_t i = 1; i < sources.size(); ++i) {
      const IcpResult& r = sequential[i];
      g.edges.push_back({i - 1, i, T_world_scan[i - 1].inverse() * r.T_target_source,
                         match_information(sources[i].points, std::max(r.rmse_m, s_.information_sigma_min_m),
                                           std::max(r.inlier_ratio, 1e-3))});
    }
    for (const SlamLoop& l : loops) {
      g.edges.push_back({l.from, l.to, l.T_from_to,
                         match_information(sources[l.to].points, std::max(l.rmse_m, s_.information_sigma_min_m),
                                           std::max(l.inlier_ratio, 1e-3))});
    }
    return g;
  }

 private:
  const SlamSettings& s_;
  const SlamProgress& progress_;
};

}  // namespace

Eigen::Matrix<double, 6, 6> match_information(const std::vector<Eigen::Vector3f>& source_points, double sigma_m,
                                              double weight) {
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (const auto& pf : source_points) {
    const Eigen::Vector3d p = pf.cast<double>();
    const Eigen::Matrix3d P = skew(p);
    H.topLeftCorner<3, 3>() += Eigen::Matrix3d::Identity();
    H.topRightCorner<3, 3>() -= P;
    H.bottomLeftCorner<3, 3>() += P;
    H.bottomRightCorner<3, 3>() -= P * P;
  }
  H *= weight / (sigma_m * sigma_m);
  // A few points on a line leave H singular; a tiny ridge keeps it a valid
  // (weak) information matrix rather than one the pose graph must refuse.
  H += 1e-9 * (1.0 + H.trace()) * Eigen::Matrix<double, 6, 6>::Identity();
  return 0.5 * (H + H.transpose());
}

SlamResult slam(std::vector<Scan> scans, const SlamSettings& settings, const SlamProgress& progress) {
  const auto start = Clock::now();
  if (scans.empty()) throw std::invalid_argument("slam: no scans");
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (scans[i].cloud.empty()) {
      throw std::invalid_argument("slam: scan " + std::to_string(i) + " ('" + scans[i].name + "') has no points");
    }
  }
  check_settings(settings);
  const Pipeline pipeline(settings, progress);
  const std::size_t n = scans.size();
  SlamResult result;

  // The odometry guess: a scan without a pose stands where the one before it did.
  std::vector<Eigen::Isometry3d> odometry(n);
  for (std::size_t i = 0; i < n; ++i) {
    odometry[i] = scans[i].T_world_scan.value_or(i == 0 ? Eigen::Isometry3d::Identity() : odometry[i - 1]);
  }

  auto t = Clock::now();
  std::vector<Cloud> clouds(n);
  std::vector<Cloud> sources;  // what is matched onto the others: thinner than the targets, or the same
  if (settings.source_voxel_m > settings.scan_voxel_m) sources.resize(n);
  pipeline.report(0, n, "preprocess");
  for (std::size_t i = 0; i < n; ++i) {
    clouds[i] = settings.scan_voxel_m > 0 ? voxel_filter(scans[i].cloud, settings.scan_voxel_m) : scans[i].cloud;
    if (settings.icp.metric == IcpMetric::PointToPlane) estimate_normals(clouds[i], settings.normals_k);
    if (settings.source_voxel_m > settings.scan_voxel_m) sources[i] = voxel_filter(clouds[i], settings.source_voxel_m);
    pipeline.report(i + 1, n, "preprocess");
  }
  if (sources.empty()) sources = clouds;
  result.timings.preprocess_s = seconds_since(t);

  std::vector<Eigen::Isometry3d> T_world_scan(n, odometry[0]);
  for (int round = 0; round < settings.relaxation_rounds; ++round) {
    t = Clock::now();
    result.sequential = pipeline.sequential(clouds, sources, odometry, T_world_scan, round == 0, result.refused);
    if (round == 0) result.T_world_scan_sequential = T_world_scan;
    result.timings.sequential_s += seconds_since(t);

    t = Clock::now();
    result.loops = pipeline.loops(clouds, sources, T_world_scan, result.loop_candidates);
    result.timings.loops_s += seconds_since(t);
    if (result.loops.empty()) {  // a chain is its own optimum: nothing (more) to relax
      if (round == 0) result.relaxation = {T_world_scan, 0, 0.0, 0.0, true};
      break;
    }

    t = Clock::now();
    pipeline.report(0, 1, "relaxation");
    result.relaxation = relax(pipeline.graph(sources, T_world_scan, result.sequential, result.loops), settings.graph);
    T_world_scan = result.relaxation.T_world_node;
    pipeline.report(1, 1, "relaxation");
    result.timings.relaxation_s += seconds_since(t);
  }
  result.T_world_scan = T_world_scan;

  t = Clock::now();
  Cloud merged;
  const bool normals = std::all_of(scans.begin(), scans.end(),
                                   [](const Scan& s) { return s.cloud.normals.size() == s.cloud.points.size(); });
  pipeline.report(0, n, "map");
  for (std::size_t i = 0; i < n; ++i) {
    Cloud part = transformed(scans[i].cloud, T_world_scan[i]);
    merged.points.insert(merged.points.end(), part.points.begin(), part.points.end());
    if (normals) merged.normals.insert(merged.normals.end(), part.normals.begin(), part.normals.end());
    pipeline.report(i + 1, n, "map");
  }
  result.map = settings.map_voxel_m > 0 ? voxel_filter(merged, settings.map_voxel_m) : std::move(merged);
  result.timings.map_s = seconds_since(t);
  result.timings.total_s = seconds_since(start);
  return result;
}

}  // namespace rise::semantic
