// Registration from its defaults on the real pairs of the shared data,
// ours against PCL's and Open3D's ICP with their usual setups, in one run
// (issue 15: "speed stays", and the pairs' references).
//
// Pairs (from RISE_TEST_DATA, default ../shared/data; a pair whose files are
// absent is skipped with a line saying so):
//   lidar-ply  small_gicp's source.ply onto target.ply, identity start;
//              reference its T_target_source.txt (a registration result).
//   lidar-pcd  the same sweeps as fast_gicp's 251371071.pcd onto
//              251370668.pcd, identity start; reference its relative.txt
//              (1.9 cm and 0.22 deg from small_gicp's).
//   3dtk       3DTK scan001 onto scan000 as read_scan reads them (config.ini's
//              range limits applied); start the odometry T0^-1 T1 from the
//              .pose files; reference slam6d's .frames (not ground truth).
//   bunny      PCL's bun0 onto bun4, identity start; reference PCL's
//              published ICP result (MANIFEST.md, orthonormalised); the
//              rotation is also compared with the Stanford registration of
//              the scans (bun.conf: bun045's quaternion, bun000 identity);
//              its translation is not, PCL's subsampled files are shifted.
//   room       PCL's room_scan2 onto room_scan1 from the NDT tutorial's
//              guess. No reference exists: the errors are against ours from
//              that guess (1 thread), and say nothing about accuracy.
// Starts: the pair's own, and four 20 deg and 1 m off the reference (2 cm
// for the bunny), start = T_ref * P with P turning about z, x, y, (1,1,1)
// and moving along x, y, z, (-1,-1,0).
//
// Every method gets the SAME raw clouds as read from the files: ours
// voxel-filters inside register_clouds (its defaults, nothing tuned), PCL
// and Open3D pair all points. All pairs but the bunny also get PCL and
// Open3D rows on both clouds voxel-filtered at 0.2 m (fast_gicp's test and
// the NDT tutorial filter so), labelled; that filtering is not timed.
// Peers: PCL IterativeClosestPoint (max correspondence 1 m, 0.05 m for the
// bunny as PCL's own test, 50 iterations, transformation epsilon 1e-8) and
// Open3D RegistrationICP point-to-point and point-to-plane (the same
// distance, ICPConvergenceCriteria(1e-6, 1e-6, 50); target normals from
// Open3D's EstimateNormals, KNN 30, not timed).
// Timing: wall clock of the registration call, search structures built
// inside it; from the pair's own start the fastest of 5 runs (ours) or 3
// (Open3D), PCL one run; from the perturbed starts one run each.
//
//   bench_registration_real_pairs [--quick] [--ours-only] [--levels] [--pair NAME]
//   --quick: one run per cell; --ours-only: no PCL, no Open3D rows;
//   --levels: each of our runs' stages (preparation, each pyramid level:
//   points, iterations, ms); --pair: only lidar-ply, lidar-pcd, 3dtk, bunny
//   or room.

#include <omp.h>
#include <pcl/registration/icp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/bench_data.hpp"
#include "bench/peer_clouds.hpp"
#include "semantic/cloud_io.hpp"
#include "semantic/icp.hpp"
#include "semantic/registration.hpp"

namespace sem = rise::semantic;
namespace o3r = open3d::pipelines::registration;
using rise::bench::iso;
using rise::bench::time_fastest;

namespace {

constexpr double kDeg = M_PI / 180.0;

struct Pair {
  std::string name;
  sem::Cloud source, target;
  Eigen::Isometry3d T_start = Eigen::Isometry3d::Identity();
  std::string start_name;
  std::optional<Eigen::Isometry3d> T_reference;  // none: ours from the start stands in
  std::string reference_name;
  std::optional<Eigen::Matrix3d> R_second;  // a second reference for the rotation alone
  std::string second_name;
  double perturbation_m = 1.0;
  double peer_distance_m = 1.0;
  double peer_voxel_m = 0.0;  // > 0: PCL and Open3D rows on clouds filtered at this voxel too
};

struct Row {
  std::string method;
  int threads = 1;
  size_t start = 0;  // index into the pair's starts
  double ms = 0.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  std::string verdict = "-";  // ours: "yes", or "no: why"
};

double rotation_deg(const Eigen::Matrix3d& R, const Eigen::Matrix3d& R_ref) {
  return Eigen::AngleAxisd(R.transpose() * R_ref).angle() / kDeg;
}
double rotation_deg(const Eigen::Isometry3d& T, const Eigen::Isometry3d& ref) { return rotation_deg(T.linear(), ref.linear()); }
double translation_m(const Eigen::Isometry3d& T, const Eigen::Isometry3d& ref) {
  return (T.translation() - ref.translation()).norm();
}

// small_gicp's and fast_gicp's references: 16 numbers, a 4x4 row-major.
Eigen::Isometry3d read_matrix(const std::string& path) {
  std::ifstream in(path);
  Eigen::Matrix4d M;
  for (int i = 0; i < 16; ++i)
    if (!(in >> M(i / 4, i % 4))) throw std::runtime_error(path + ": expected 16 numbers (a row-major 4x4), number " +
                                                           std::to_string(i + 1) + " is missing or not a number");
  return iso(M);
}

// Four starts 20 deg and `move_m` off T (the registration test's).
std::vector<Eigen::Isometry3d> starts_around(const Eigen::Isometry3d& T, double move_m) {
  const Eigen::Vector3d axes[] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}};
  const Eigen::Vector3d moves[] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, -1, 0}};
  std::vector<Eigen::Isometry3d> starts;
  for (int k = 0; k < 4; ++k) {
    Eigen::Isometry3d P = Eigen::Isometry3d::Identity();
    P.linear() = Eigen::AngleAxisd(20.0 * kDeg, axes[k].normalized()).toRotationMatrix();
    P.translation() = move_m * moves[k].normalized();
    starts.push_back(T * P);
  }
  return starts;
}
const char* const kPerturbedNames[] = {"z20,+x", "x20,+y", "y20,+z", "111-20,-xy"};

std::optional<std::string> file(const std::string& relative) { return rise::bench::data_file(nullptr, "pointclouds/" + relative); }

sem::RegistrationResult ours(const Pair& pair, const Eigen::Isometry3d& start, int threads) {
  sem::RegistrationSettings s;
  s.threads = threads;
  return sem::register_clouds(pair.source, pair.target, start, s);
}

// The starts of a pair: its own first, then the four perturbed ones.
struct Starts {
  std::vector<Eigen::Isometry3d> T;
  std::vector<std::string> names;
};

// Where one run of ours spent its time (--levels).
void print_levels(const std::string& start, int threads, const sem::RegistrationResult& r) {
  std::printf("  stages of ours, start %s, %d thread(s): %.1f ms in all, %.1f ms preparing%s\n", start.c_str(), threads,
              1e3 * r.total_s, 1e3 * r.prepare_s, r.from_start ? ", the answer from the start's run" : "");
  for (const auto& l : r.levels)
    std::printf("    voxel %6.3f m pairing %6.3f m  %6zu onto %6zu points  %3d iterations%s  %7.1f ms\n", l.voxel_m, l.pairing_m,
                l.source_points, l.target_points, l.icp.iterations, l.icp.converged ? " (converged)" : "            ",
                1e3 * l.seconds);
}

// Ours from every start (the pair's own: the fastest of 5 runs, or 1 with
// --quick; the perturbed: one run each), on 1 and 2 threads. Without a
// reference, ours from the pair's own start stands in for it.
std::vector<Row> ours_rows(Pair& pair, Starts& starts, bool quick, bool levels) {
  std::vector<Row> rows;
  const auto run_ours = [&](size_t start, int runs) {
    for (int threads : {1, 2}) {
      sem::RegistrationResult r;
      const double ms = time_fastest<sem::RegistrationResult>(runs, [&] { return ours(pair, starts.T[start], threads); }, r);
      rows.push_back({"ours register_clouds", threads, start, ms, r.T_target_source, r.converged ? "yes" : "no: " + r.failure});
      if (levels) print_levels(starts.names[start], threads, r);
    }
  };
  run_ours(0, quick ? 1 : 5);
  if (!pair.T_reference) {
    pair.T_reference = rows.front().T;
    pair.reference_name = "ours from the " + pair.start_name + " (NO reference exists: errors say nothing about accuracy)";
  }
  for (size_t k = 0; k < 4; ++k) {
    starts.T.push_back(starts_around(*pair.T_reference, pair.perturbation_m)[k]);
    starts.names.push_back(kPerturbedNames[k]);
    run_ours(starts.T.size() - 1, 1);
  }
  return rows;
}

// The clouds as PCL's and Open3D's ICP take them, with a label for the rows.
struct PeerInput {
  std::string label;
  pcl::PointCloud<pcl::PointXYZ>::Ptr source_pcl, target_pcl;
  open3d::geometry::PointCloud source_o3d, target_o3d;
};

// The peers' inputs: the raw clouds and (lidar pairs) filtered ones.
std::vector<PeerInput> peer_inputs(const Pair& pair) {
  std::vector<PeerInput> inputs;
  const auto add_input = [&](const std::string& label, const sem::Cloud& source, const sem::Cloud& target) {
    PeerInput in{label, rise::bench::to_pcl(source), rise::bench::to_pcl(target), {}, {}};
    in.source_o3d.points_.reserve(source.size());
    for (const auto& p : source.points) in.source_o3d.points_.push_back(p.cast<double>());
    for (const auto& p : target.points) in.target_o3d.points_.push_back(p.cast<double>());
    in.target_o3d.EstimateNormals(open3d::geometry::KDTreeSearchParamKNN(30));
    inputs.push_back(std::move(in));
  };
  add_input("", pair.source, pair.target);
  if (pair.peer_voxel_m > 0.0) {
    char label[32];
    std::snprintf(label, sizeof label, ", voxel %.1f m", pair.peer_voxel_m);
    add_input(label, sem::voxel_filter(pair.source, pair.peer_voxel_m), sem::voxel_filter(pair.target, pair.peer_voxel_m));
  }
  return inputs;
}

// PCL's ICP (one run) and Open3D's point-to-point and point-to-plane (1 and
// 2 threads; the fastest of 3 from the pair's own start) from every start.
void add_peer_rows(const Pair& pair, const Starts& starts, bool quick, std::vector<Row>& rows) {
  const double r = pair.peer_distance_m;
  for (const auto& in : peer_inputs(pair))
    for (size_t start = 0; start < starts.T.size(); ++start) {
      const Eigen::Matrix4d T0 = starts.T[start].matrix();
      Eigen::Isometry3d T;
      const double ms = time_fastest<Eigen::Isometry3d>(1, [&] {
        // A new object each run: PCL builds its k-d tree inside align, once per target.
        pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
        icp.setInputSource(in.source_pcl);
        icp.setInputTarget(in.target_pcl);
        icp.setMaxCorrespondenceDistance(r);
        icp.setMaximumIterations(50);
        icp.setTransformationEpsilon(1e-8);
        pcl::PointCloud<pcl::PointXYZ> out;
        icp.align(out, T0.cast<float>());
        return iso(icp.getFinalTransformation().cast<double>());
      }, T);
      rows.push_back({"PCL IterativeClosestPoint" + in.label, 1, start, ms, T, "-"});

      const o3r::ICPConvergenceCriteria criteria(1e-6, 1e-6, 50);
      const int runs = start == 0 && !quick ? 3 : 1;
      for (int plane = 0; plane < 2; ++plane)
        for (int threads : {1, 2}) {
          omp_set_num_threads(threads);
          const double o3d_ms = time_fastest<Eigen::Isometry3d>(runs, [&] {
            const auto res = plane ? o3r::RegistrationICP(in.source_o3d, in.target_o3d, r, T0,
                                                          o3r::TransformationEstimationPointToPlane(), criteria)
                                   : o3r::RegistrationICP(in.source_o3d, in.target_o3d, r, T0,
                                                          o3r::TransformationEstimationPointToPoint(), criteria);
            return iso(res.transformation_);
          }, T);
          rows.push_back({(plane ? "Open3D point-to-plane" : "Open3D point-to-point") + in.label, threads, start, o3d_ms, T, "-"});
        }
    }
}

// The table, start by start.
void print_rows(const Pair& pair, const Starts& starts, const std::vector<Row>& rows) {
  const Eigen::Isometry3d& ref = *pair.T_reference;
  std::printf("\n%s: source %zu, target %zu points; errors vs %s", pair.name.c_str(), pair.source.size(), pair.target.size(),
              pair.reference_name.c_str());
  if (pair.R_second) std::printf("; \"%s\": rotation error vs %s", pair.second_name.c_str(), pair.second_name.c_str());
  std::printf("\n");
  for (size_t k = 0; k < starts.T.size(); ++k)
    std::printf("  start %-12s %7.3f deg %7.3f m from the reference\n", starts.names[k].c_str(),
                rotation_deg(starts.T[k], ref), translation_m(starts.T[k], ref));
  std::printf("%-38s %7s %-12s %9s %10s %10s", "method", "threads", "start", "ms", "rot err deg", "trans err m");
  if (pair.R_second) std::printf(" %9s", pair.second_name.c_str());
  std::printf("  converged (ours)\n");
  for (const auto& row : rows) {
    std::printf("%-38s %7d %-12s %9.1f %10.4f %10.4f", row.method.c_str(), row.threads, starts.names[row.start].c_str(), row.ms,
                rotation_deg(row.T, ref), translation_m(row.T, ref));
    if (pair.R_second) std::printf(" %9.4f", rotation_deg(row.T.linear(), *pair.R_second));
    std::printf("  %s\n", row.verdict.c_str());
  }
}

// Against the goals, from the pair's own start; errors within 0.01 deg and
// 1 mm count as equal (the references are registration results).
void print_speedups(const Pair& pair, const std::vector<Row>& rows, bool reference_is_ours) {
  const Eigen::Isometry3d& ref = *pair.T_reference;
  const auto find = [&](const std::string& method, int threads) -> const Row* {
    for (const auto& row : rows)
      if (row.method == method && row.threads == threads && row.start == 0) return &row;
    return nullptr;
  };
  const Row* mine = find("ours register_clouds", 2);
  const auto no_worse = [&](const Row& theirs) {
    return rotation_deg(mine->T, ref) <= rotation_deg(theirs.T, ref) + 0.01 &&
           translation_m(mine->T, ref) <= translation_m(theirs.T, ref) + 0.001;
  };
  const auto against = [&](const char* name, const Row* theirs, double goal) {
    if (!theirs) return;
    const double speedup = theirs->ms / mine->ms;
    std::printf("  %s: %.1fx (goal >= %.0fx: %s), error %.3f deg / %.4f m against ours %.3f deg / %.4f m: ours <= theirs: %s\n",
                name, speedup, goal, speedup >= goal ? "met" : "NOT met", rotation_deg(theirs->T, ref),
                translation_m(theirs->T, ref), rotation_deg(mine->T, ref), translation_m(mine->T, ref),
                reference_is_ours ? "not measurable, the reference is ours" : no_worse(*theirs) ? "yes" : "no");
  };
  std::printf("%s, speed-up of ours (2 threads) from the start \"%s\":\n", pair.name.c_str(), pair.start_name.c_str());
  against("over PCL ICP (1 thread)", find("PCL IterativeClosestPoint", 1), 10.0);
  against("over Open3D point-to-point (2 threads)", find("Open3D point-to-point", 2), 2.0);
}

// Every start, every method: within 5 cm and 1 deg of the reference?
void print_tally(const Pair& pair, const Starts& starts, const std::vector<Row>& rows) {
  const Eigen::Isometry3d& ref = *pair.T_reference;
  std::vector<std::pair<std::string, int>> tally;  // method (threads) -> starts within
  bool all_ours = true;
  for (const auto& row : rows) {
    const bool within = rotation_deg(row.T, ref) <= 1.0 && translation_m(row.T, ref) <= 0.05;
    const std::string key = row.method + " (" + std::to_string(row.threads) + ")";
    auto it = std::find_if(tally.begin(), tally.end(), [&](const auto& t) { return t.first == key; });
    if (it == tally.end()) it = tally.insert(tally.end(), {key, 0});
    it->second += within;
    if (row.method == "ours register_clouds" && !within) all_ours = false;
  }
  std::printf("%s: ours within 5 cm and 1 deg of the reference from every start: %s. Starts within, of %zu:", pair.name.c_str(),
              all_ours ? "yes" : "NO", starts.T.size());
  for (const auto& [method, n] : tally) std::printf(" %s %d;", method.c_str(), n);
  std::printf("\n");
}

void run_pair(Pair& pair, bool quick, bool ours_only, bool levels) {
  Starts starts{{pair.T_start}, {pair.start_name}};
  const bool reference_is_ours = !pair.T_reference;
  std::vector<Row> rows = ours_rows(pair, starts, quick, levels);
  // The peers, on the raw clouds and (lidar pairs) on filtered ones.
  if (!ours_only) add_peer_rows(pair, starts, quick, rows);
  print_rows(pair, starts, rows);
  if (!ours_only) print_speedups(pair, rows, reference_is_ours);
  print_tally(pair, starts, rows);
}

// Each pair reads its files when it is its turn (and only if they are all there).
struct Maker {
  std::string name;
  std::vector<std::string> files;  // under pointclouds/
  std::function<Pair(const std::vector<std::string>&)> make;
};

std::vector<Maker> pair_makers() {
  return {
    {"lidar-ply", {"koide3_small_gicp/source.ply", "koide3_small_gicp/target.ply", "koide3_small_gicp/T_target_source.txt"},
     [](const std::vector<std::string>& f) {
       Pair p;
       p.name = "lidar-ply";
       p.source = sem::read_cloud(f[0]);
       p.target = sem::read_cloud(f[1]);
       p.start_name = "identity";
       p.T_reference = read_matrix(f[2]);
       p.reference_name = "small_gicp's T_target_source.txt";
       p.peer_voxel_m = 0.2;
       return p;
     }},
    {"lidar-pcd", {"koide3_fast_gicp/251371071.pcd", "koide3_fast_gicp/251370668.pcd", "koide3_fast_gicp/relative.txt"},
     [](const std::vector<std::string>& f) {
       Pair p;
       p.name = "lidar-pcd";
       p.source = sem::read_cloud(f[0]);
       p.target = sem::read_cloud(f[1]);
       p.start_name = "identity";
       p.T_reference = read_matrix(f[2]);
       p.reference_name = "fast_gicp's relative.txt";
       p.peer_voxel_m = 0.2;
       return p;
     }},
    {"3dtk", {"3DTK-dat/scan001.3d", "3DTK-dat/scan000.3d", "3DTK-dat/scan001.frames", "3DTK-dat/scan000.frames"},
     [](const std::vector<std::string>& f) {
       const sem::Scan s1 = sem::read_scan(f[0]), s0 = sem::read_scan(f[1]);
       if (!s0.T_world_scan || !s1.T_world_scan) throw std::runtime_error("3DTK-dat: scan000.pose or scan001.pose is absent");
       Pair p;
       p.name = "3dtk";
       p.source = s1.cloud;
       p.target = s0.cloud;
       p.T_start = s0.T_world_scan->inverse() * *s1.T_world_scan;
       p.start_name = "odometry";
       p.T_reference = sem::read_3dtk_frames(f[3]).back().inverse() * sem::read_3dtk_frames(f[2]).back();
       p.reference_name = "slam6d's .frames";
       p.peer_voxel_m = 0.2;
       return p;
     }},
    {"bunny", {"pcl/bun0.pcd", "pcl/bun4.pcd"},
     [](const std::vector<std::string>& f) {
       Pair p;
       p.name = "bunny";
       p.source = sem::read_cloud(f[0]);
       p.target = sem::read_cloud(f[1]);
       p.start_name = "identity";
       Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
       M.topRows<3>() << 0.8806, 0.0365, -0.4724, 0.03453, -0.02354, 0.9992, 0.03326, -0.001519, 0.4732, -0.01817, 0.8808,
           0.04116;
       p.T_reference = iso(M);
       p.reference_name = "PCL's published ICP result";
       // bun.conf: bun045's pose (bun000 at identity); its rotation, not
       // its inverse's, is bun4 <- bun0 in PCL's files.
       p.R_second = Eigen::Quaterniond(0.955586, 0.00548449, -0.294635, -0.0038555).normalized().toRotationMatrix();
       p.second_name = "Stanford";
       p.perturbation_m = 0.02;
       p.peer_distance_m = 0.05;
       return p;
     }},
    {"room", {"PointCloudLibrary_data/room_scan2.pcd", "PointCloudLibrary_data/room_scan1.pcd"},
     [](const std::vector<std::string>& f) {
       Pair p;
       p.name = "room";
       p.source = sem::read_cloud(f[0]);
       p.target = sem::read_cloud(f[1]);
       p.T_start = Eigen::Translation3d(1.79387, 0.720047, 0) * Eigen::AngleAxisd(0.6931, Eigen::Vector3d::UnitZ());
       p.start_name = "NDT guess";  // the tutorial's
       p.peer_voxel_m = 0.2;
       return p;
     }},
  };
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, ours_only = false, levels = false;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--ours-only") == 0) {
      ours_only = true;
    } else if (std::strcmp(argv[i], "--levels") == 0) {
      levels = true;
    } else if (std::strcmp(argv[i], "--pair") == 0 && i + 1 < argc) {
      only = argv[++i];
    } else {
      std::fprintf(stderr, "usage: bench_registration_real_pairs [--quick] [--ours-only] [--levels] [--pair lidar-ply|lidar-pcd|3dtk|bunny|room]\n");
      return 2;
    }
  }
  std::printf("register_clouds from its defaults vs PCL %s ICP vs Open3D ICP on the real pairs, %d hardware threads%s\n",
              PCL_VERSION_PRETTY, omp_get_num_procs(), quick ? " (--quick: one run per cell)" : "");

  const std::vector<Maker> makers = pair_makers();
  int ran = 0;
  for (const auto& m : makers) {
    if (!only.empty() && m.name != only) continue;
    std::vector<std::string> paths;
    for (const auto& f : m.files)
      if (const auto path = file(f)) paths.push_back(*path);
    if (paths.size() != m.files.size()) {
      std::printf("\n%s: skipped, its files are not all in the data (see stderr)\n", m.name.c_str());
      continue;
    }
    try {
      Pair p = m.make(paths);
      run_pair(p, quick, ours_only, levels);
      ++ran;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_registration_real_pairs: %s: %s\n", m.name.c_str(), e.what());
      return 1;
    }
  }
  if (ran == 0) {
    std::fprintf(stderr, "bench_registration_real_pairs: no pair ran (set RISE_TEST_DATA%s)\n",
                 only.empty() ? "" : ", or check --pair");
    return 1;
  }
  return 0;
}
