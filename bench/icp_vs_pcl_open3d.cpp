// ICP, 30 iterations, ours (1 and 2 threads) against PCL's
// IterativeClosestPoint and GeneralizedIterativeClosestPoint and Open3D's
// RegistrationICP (point-to-point and point-to-plane), same inputs, same
// initial guess, same pairing distance, in one run (issue 6, Performance).
//
// Pairs (from RISE_TEST_DATA, default ../shared/data):
//   3dtk-17k   3DTK scan001 onto scan000 (range 0.48 .. 32.7 m), voxel
//              filtered to ~17k points; odometry start; reference: slam6d's
//              .frames (not ground truth).
//   3dtk-78k   the same scans unfiltered (~78k points).
//   office-100k PCL's office1 Kinect frame voxel filtered to ~100k points;
//              the source is the same cloud moved by a known motion (5 deg,
//              12 cm) with 2 mm noise, identity start: ground truth known.
// Timing: wall clock of the registration call (nearest-neighbour structure
// build included, as each library does it inside), the fastest of 7 runs
// (ours), 3 (Open3D) or 1 (PCL); normals for the
// point-to-plane rows are estimated beforehand and not timed. rmse and
// inliers are evaluated the same way for every method: nearest target point
// within the pairing distance after applying its transform.
//
//   bench_icp_vs_pcl_open3d [--quick] [--ours-only] [--pair NAME]
//   --quick: one run per cell; --ours-only: no PCL, no Open3D rows;
//   --pair: only the pair of that name.

#include <omp.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/icp.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>
#include <random>
#include <string>
#include <vector>

#include "bench/peer_clouds.hpp"
#include "semantic/cloud_io.hpp"
#include "semantic/icp.hpp"
#include "semantic/voxel_grid.hpp"

namespace sem = rise::semantic;
namespace o3r = open3d::pipelines::registration;
using rise::bench::iso;
using rise::bench::to_open3d;
using rise::bench::to_pcl;

namespace {

struct Pair {
  std::string name;
  sem::Cloud source, target;  // target with normals (for the point-to-plane rows)
  Eigen::Isometry3d T_initial = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_reference = Eigen::Isometry3d::Identity();
  std::string reference;  // "truth" or "slam6d"
  double max_correspondence_m = 0.25;
};

struct Row {
  std::string method;
  int threads;
  double ms;
  Eigen::Isometry3d T;
};

std::string data_root() {
  if (const char* e = std::getenv("RISE_TEST_DATA")) return e;
  return (std::filesystem::path(RISE_SOURCE_DIR) / ".." / "shared" / "data").lexically_normal().string();
}

sem::Cloud in_range(const sem::Cloud& c) {
  sem::Cloud out;
  for (const auto& p : c.points)
    if (p.norm() >= 0.48f && p.norm() < 32.7f) out.points.push_back(p);
  return out;
}

// The leaf that leaves about `points` points (bisection on the count).
sem::Cloud filter_to(const sem::Cloud& c, size_t points) {
  double lo = 1e-3, hi = 2.0;
  sem::Cloud best = c;
  for (int i = 0; i < 24; ++i) {
    const double leaf = std::sqrt(lo * hi);
    sem::Cloud f = sem::voxel_filter(c, leaf);
    if (f.size() > points) lo = leaf; else hi = leaf;
    best = std::move(f);
    if (std::abs(static_cast<double>(best.size()) - static_cast<double>(points)) < 0.01 * static_cast<double>(points)) break;
  }
  return best;
}

void run_pair(const Pair& pair, bool quick, bool ours_only) {
  constexpr int kIterations = 30;
  const int reps = quick ? 1 : 3;  // ours 2 * reps + 1 runs, Open3D reps, PCL one (seconds each)
  std::vector<Row> rows;
  const double r = pair.max_correspondence_m;

  const auto time_it = [](int n, const std::function<Eigen::Isometry3d()>& f, Eigen::Isometry3d& T) {
    return rise::bench::time_fastest(n, f, T);
  };

  struct Variant {
    sem::IcpMetric metric;
    bool exact;
    bool reuse;
    int coarse_stride;
    const char* name;
  };
  const Variant variants[] = {
      {sem::IcpMetric::PointToPoint, false, true, 8, "ours point-to-point"},
      {sem::IcpMetric::PointToPoint, false, true, 1, "ours point-to-point, all points"},
      {sem::IcpMetric::PointToPoint, false, false, 1, "ours point-to-point, all, no pair reuse"},
      {sem::IcpMetric::PointToPoint, true, true, 1, "ours point-to-point, all, exact pairs"},
      {sem::IcpMetric::PointToPlane, false, true, 8, "ours point-to-plane"}};
  for (const auto& v : variants)
    for (int threads : {1, 2}) {
      sem::IcpSettings s;
      s.metric = v.metric;
      s.exact_neighbours = v.exact;
      s.reuse_pairs = v.reuse;
      s.coarse_stride = v.coarse_stride;
      s.max_iterations = kIterations;
      s.max_correspondence_m = s.min_correspondence_m = r;
      s.translation_epsilon_m = s.rotation_epsilon_rad = 0.0;  // all 30 iterations, as the peers
      s.threads = threads;
      Eigen::Isometry3d T;
      const double ms = time_it(reps * 2 + 1, [&] { return sem::icp(pair.source, pair.target, pair.T_initial, s).T_target_source; }, T);
      rows.push_back({v.name, threads, ms, T});
    }

  if (!ours_only) {
    const auto src = to_pcl(pair.source), tgt = to_pcl(pair.target);
    pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
    icp.setInputSource(src);
    icp.setInputTarget(tgt);
    icp.setMaximumIterations(kIterations);
    icp.setMaxCorrespondenceDistance(r);
    icp.setTransformationEpsilon(0.0);
    icp.setEuclideanFitnessEpsilon(0.0);
    pcl::PointCloud<pcl::PointXYZ> out;
    Eigen::Isometry3d T;
    const double ms = time_it(1, [&] {
      icp.align(out, pair.T_initial.matrix().cast<float>());
      return iso(icp.getFinalTransformation().cast<double>());
    }, T);
    rows.push_back({"PCL IterativeClosestPoint", 1, ms, T});

    pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
    gicp.setInputSource(src);
    gicp.setInputTarget(tgt);
    gicp.setMaximumIterations(kIterations);
    gicp.setMaxCorrespondenceDistance(r);
    gicp.setTransformationEpsilon(0.0);
    const double gms = time_it(1, [&] {
      gicp.align(out, pair.T_initial.matrix().cast<float>());
      return iso(gicp.getFinalTransformation().cast<double>());
    }, T);
    rows.push_back({"PCL GeneralizedIterativeClosestPoint", 1, gms, T});
  }

  if (!ours_only) {
    const auto src = to_open3d(pair.source), tgt = to_open3d(pair.target);
    const o3r::ICPConvergenceCriteria criteria(0.0, 0.0, kIterations);
    for (int plane = 0; plane < 2; ++plane)
      for (int threads : {1, 2}) {
        omp_set_num_threads(threads);
        Eigen::Isometry3d T;
        const double ms = time_it(reps, [&] {
          const auto res = plane ? o3r::RegistrationICP(src, tgt, r, pair.T_initial.matrix(),
                                                        o3r::TransformationEstimationPointToPlane(), criteria)
                                 : o3r::RegistrationICP(src, tgt, r, pair.T_initial.matrix(),
                                                        o3r::TransformationEstimationPointToPoint(), criteria);
          return iso(res.transformation_);
        }, T);
        rows.push_back({plane ? "Open3D RegistrationICP point-to-plane" : "Open3D RegistrationICP point-to-point", threads, ms, T});
      }
  }

  // The same evaluation for every row.
  const sem::VoxelGrid grid(pair.target.points, static_cast<float>(2.0 * r));
  std::printf("\n%s: source %zu, target %zu points, pairing distance %.2f m, %d iterations, errors vs %s\n",
              pair.name.c_str(), pair.source.size(), pair.target.size(), r, kIterations, pair.reference.c_str());
  std::printf("%-40s %7s %9s %12s %12s %10s %8s\n", "method", "threads", "ms", "rot err deg", "trans err m", "rmse m", "inliers");
  for (const auto& row : rows) {
    double se = 0.0;
    size_t pairs = 0;
    const Eigen::Isometry3f Tf = row.T.cast<float>();
    for (const auto& p : pair.source.points) {
      const auto nb = grid.nearest(Tf * p, static_cast<float>(r));
      if (nb.index == sem::VoxelGrid::kNone) continue;
      se += nb.distance2_m2;
      ++pairs;
    }
    const double rot = Eigen::AngleAxisd(row.T.linear().transpose() * pair.T_reference.linear()).angle() * 180.0 / M_PI;
    const double trans = (row.T.translation() - pair.T_reference.translation()).norm();
    std::printf("%-40s %7d %9.1f %12.4f %12.4f %10.5f %8.3f\n", row.method.c_str(), row.threads, row.ms, rot, trans,
                pairs ? std::sqrt(se / static_cast<double>(pairs)) : 0.0,
                static_cast<double>(pairs) / static_cast<double>(pair.source.size()));
  }
  const auto ms_of = [&](const std::string& m, int threads) {
    for (const auto& row : rows)
      if (row.method == m && row.threads == threads) return row.ms;
    return 0.0;
  };
  const double ours2 = ms_of("ours point-to-point", 2), ours_plane2 = ms_of("ours point-to-plane", 2);
  std::printf("speed-up, 2 threads: %.1fx PCL ICP (goal >= 10x), %.1fx Open3D point-to-point (goal >= 2x), "
              "%.1fx Open3D point-to-plane\n",
              ms_of("PCL IterativeClosestPoint", 1) / ours2,
              ms_of("Open3D RegistrationICP point-to-point", 2) / ours2,
              ms_of("Open3D RegistrationICP point-to-plane", 2) / ours_plane2);
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, ours_only = false;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--ours-only") == 0) {
      ours_only = true;
    } else if (std::strcmp(argv[i], "--pair") == 0 && i + 1 < argc) {
      only = argv[++i];
    } else {
      std::fprintf(stderr, "usage: bench_icp_vs_pcl_open3d [--quick] [--ours-only] [--pair 3dtk-17k|3dtk-78k|office-100k]\n");
      return 2;
    }
  }
  const std::string root = data_root();
  const std::string dtk = root + "/pointclouds/3DTK-dat", office = root + "/pointclouds/pcl/office1.pcd";
  if (!std::filesystem::exists(dtk + "/scan000.3d") || !std::filesystem::exists(office)) {
    std::fprintf(stderr, "bench_icp_vs_pcl_open3d: data not found under %s (set RISE_TEST_DATA)\n", root.c_str());
    return 1;
  }
  std::printf("ICP, 30 iterations: ours vs PCL %s vs Open3D (Debian libopen3d 0.16), %d hardware threads\n",
              PCL_VERSION_PRETTY, omp_get_num_procs());

  const sem::Scan s0 = sem::read_scan(dtk + "/scan000.3d"), s1 = sem::read_scan(dtk + "/scan001.3d");
  const Eigen::Isometry3d slam6d =
      sem::read_3dtk_frames(dtk + "/scan000.frames").back().inverse() * sem::read_3dtk_frames(dtk + "/scan001.frames").back();
  const Eigen::Isometry3d odometry = s0.T_world_scan->inverse() * *s1.T_world_scan;

  std::vector<Pair> pairs;
  {
    Pair p{"3dtk-17k", filter_to(in_range(s1.cloud), 17000), filter_to(in_range(s0.cloud), 17000), odometry, slam6d, "slam6d", 0.25};
    pairs.push_back(std::move(p));
    Pair q{"3dtk-78k", in_range(s1.cloud), in_range(s0.cloud), odometry, slam6d, "slam6d", 0.25};
    pairs.push_back(std::move(q));
  }
  {
    const sem::Cloud o = filter_to(sem::read_cloud(office), 100000);
    Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
    T_true.linear() = (Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d(0.2, 1.0, 0.1).normalized())).toRotationMatrix();
    T_true.translation() = Eigen::Vector3d(0.08, -0.06, 0.07);
    sem::Cloud src = sem::transformed(o, T_true.inverse());
    std::mt19937 rng(1);
    std::normal_distribution<float> noise(0.0f, 0.002f);
    for (auto& p : src.points) p += Eigen::Vector3f(noise(rng), noise(rng), noise(rng));
    Pair p{"office-100k", std::move(src), o, Eigen::Isometry3d::Identity(), T_true, "truth", 0.3};
    pairs.push_back(std::move(p));
  }
  for (auto& p : pairs) {
    if (!only.empty() && p.name != only) continue;
    sem::estimate_normals(p.target, 10);  // both sensors sit at their cloud's origin
    run_pair(p, quick, ours_only);
  }
  return 0;
}
