// relax() on the public pose-graph benchmarks in shared/data/posegraphs
// (MANIFEST.md section 6; issue 15: "time, final cost, and the error against
// sphere2500's ground truth"): per graph its size, the read time, and on 1
// and 2 threads relax()'s time, iterations, initial and final cost
// (½ Σ rᵀ·Ω·r, PoseGraphResult) and whether Ceres converged. For sphere2500
// the absolute trajectory error against borglab/gtsam's noise-free
// sphere2500_groundtruth.txt, before and after relaxation, aligned two ways:
// "anchored" (the rigid transform that takes pose 0 onto ground-truth pose
// 0: both are the identity, and relax() holds pose 0 fixed) and "best fit"
// (Umeyama's least-squares rigid fit of the positions, no scale).
//
// Usage: bench_pose_graph_relaxation [max_iterations=PoseGraphSettings'] [runs=1]
//        (the best time of `runs` is printed)

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "bench/bench_data.hpp"
#include "semantic/pose_graph.hpp"
#include "semantic/pose_graph_io.hpp"

namespace {

using rise::semantic::PoseGraphFile;
using Poses = std::vector<Eigen::Isometry3d>;
constexpr double kDeg = M_PI / 180.0;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Ate {
  double translation_m = 0.0, rotation_deg = 0.0;  // RMS
};

Ate ate(const Poses& estimate, const Poses& truth, const Eigen::Isometry3d& T_truth_estimate) {
  double t2 = 0.0, r2 = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const Eigen::Isometry3d E = truth[i].inverse() * T_truth_estimate * estimate[i];
    t2 += E.translation().squaredNorm();
    const double angle = Eigen::AngleAxisd(E.linear()).angle();
    r2 += angle * angle;
  }
  const double n = static_cast<double>(truth.size());
  return {std::sqrt(t2 / n), std::sqrt(r2 / n) / kDeg};
}

Eigen::Isometry3d best_fit(const Poses& estimate, const Poses& truth) {
  Eigen::Matrix3Xd from(3, estimate.size()), to(3, truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    from.col(static_cast<Eigen::Index>(i)) = estimate[i].translation();
    to.col(static_cast<Eigen::Index>(i)) = truth[i].translation();
  }
  return Eigen::Isometry3d(Eigen::umeyama(from, to, false));
}

void print_ate(const char* what, const Poses& estimate, const Poses& truth) {
  const Ate anchored = ate(estimate, truth, truth[0] * estimate[0].inverse());
  const Ate fit = ate(estimate, truth, best_fit(estimate, truth));
  std::printf("| %s | %.3f | %.2f | %.3f | %.2f |\n", what, anchored.translation_m, anchored.rotation_deg,
              fit.translation_m, fit.rotation_deg);
}

}  // namespace

int main(int argc, char** argv) {
  rise::semantic::PoseGraphSettings settings;
  if (argc > 1) settings.max_iterations = std::atoi(argv[1]);
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 1;
  const char* dir = "posegraphs/david-m-rosen_SE-Sync/";
  const char* graphs[] = {"intel", "MIT", "CSAIL", "manhattan", "sphere2500", "parking-garage"};

  std::printf("max_iterations %d, best of %d run(s)\n\n", settings.max_iterations, runs);
  std::printf("| graph | nodes | edges | loops | read s | start | threads | relax s | cpu s | iterations | initial cost | start cost | final cost | converged |\n");
  std::printf("|---|--:|--:|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|---|\n");
  Poses sphere_initial, sphere_relaxed;
  std::vector<long long> sphere_ids;
  rise::semantic::PoseGraph sphere_graph;
  int missing = 0;
  for (const char* name : graphs) {
    const auto path = rise::bench::data_file(nullptr, std::string(dir) + name + ".g2o");
    if (!path) {
      ++missing;
      continue;
    }
    const auto t_read = std::chrono::steady_clock::now();
    const PoseGraphFile f = rise::semantic::read_pose_graph(*path);
    const double read_s = seconds_since(t_read);
    for (const bool chordal : {false, true})
    for (const int threads : {1, 2}) {
      settings.threads = threads;
      settings.chordal_initialization = chordal;
      rise::semantic::PoseGraphResult r;
      double best_s = 1e300, cpu_s = 0.0;
      for (int k = 0; k < runs; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        const std::clock_t c0 = std::clock();
        r = rise::semantic::relax(f.graph, settings);
        const double s = seconds_since(t0);
        if (s < best_s) best_s = s, cpu_s = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
      }
      std::printf("| %s | %zu | %zu | %zu | %.3f | %s | %d | %.3f | %.3f | %d | %.6g | %.6g | %.6g | %s |\n", name,
                  f.graph.T_world_node.size(), f.graph.edges.size(), f.loop_closures, read_s, chordal ? "chordal" : (f.chained ? "chain" : "file"), threads, best_s, cpu_s,
                  r.iterations, r.initial_cost, r.start_cost, r.final_cost, r.converged ? "yes" : "no");
      std::fflush(stdout);
      if (std::string(name) == "sphere2500" && !chordal) {
        sphere_initial = f.graph.T_world_node;
        sphere_relaxed = r.T_world_node;
        sphere_ids = f.ids;
        sphere_graph = f.graph;
      }
    }
  }

  const auto truth_path = rise::bench::data_file(nullptr, "posegraphs/borglab_gtsam/sphere2500_groundtruth.txt");
  if (!truth_path || sphere_relaxed.empty()) {
    std::printf("\nsphere2500 ground truth: not compared (a file is absent)\n");
    return 1;
  }
  const PoseGraphFile truth = rise::semantic::read_pose_graph(*truth_path);
  if (truth.ids != sphere_ids) {
    std::printf("\nsphere2500 ground truth: its vertex ids are not the g2o file's, in the same order\n");
    return 1;
  }
  std::printf("\nsphere2500 against the ground truth (RMS over %zu poses)\n\n", sphere_relaxed.size());
  std::printf("| poses | anchored at pose 0: m | deg | best fit (Umeyama): m | deg |\n|---|--:|--:|--:|--:|\n");
  print_ate("initial (g2o vertices)", sphere_initial, truth.graph.T_world_node);
  print_ate("relaxed", sphere_relaxed, truth.graph.T_world_node);

  // Whether the minimum reached is the one next to the truth: relax the
  // noisy graph again, starting from the ground truth.
  rise::semantic::PoseGraph from_truth = sphere_graph;
  from_truth.T_world_node = truth.graph.T_world_node;
  settings.chordal_initialization = false;
  const auto r = rise::semantic::relax(from_truth, settings);
  std::printf("\nsphere2500 relaxed from the ground truth: cost %.6g -> %.6g in %d iterations\n", r.initial_cost,
              r.final_cost, r.iterations);
  return missing == 0 ? 0 : 1;
}
