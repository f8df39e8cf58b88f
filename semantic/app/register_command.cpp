#include "semantic/app/register_command.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "semantic/cloud_io.hpp"
#include "semantic/icp.hpp"
#include "semantic/registration.hpp"

namespace rise::semantic {
namespace {

struct RegisterOptions {
  std::string source, target;
  std::string init, init_file;
  std::string metric;
  bool metric_given = false;
  double voxel_m = 0.0, coarse_voxel_m = 0.0;
  double min_inlier_ratio = RegistrationSettings{}.min_inlier_ratio;
  bool plain = false;  // one ICP at the given pairing distances instead of the pyramid
  int iterations = IcpSettings{}.max_iterations;
  double max_dist_m = IcpSettings{}.max_correspondence_m;
  double min_dist_m = IcpSettings{}.min_correspondence_m;
  double huber_m = 0.0;
  int threads = 0;
  bool exact = false;
  int coarse_stride = IcpSettings{}.coarse_stride;
};

// 16 numbers, row-major, the last row 0 0 0 1.
Eigen::Isometry3d parse_matrix(const std::string& text, const std::string& where) {
  std::istringstream in(text);
  std::vector<double> v;
  for (std::string w; in >> w;) {
    try {
      size_t used = 0;
      v.push_back(std::stod(w, &used));
      if (used != w.size()) throw std::invalid_argument(w);
    } catch (const std::exception&) {
      throw std::runtime_error(where + ": not a number: '" + w + "'");
    }
  }
  if (v.size() != 16) throw std::runtime_error(where + ": expected 16 numbers (row-major 4x4), found " + std::to_string(v.size()));
  Eigen::Matrix4d M;
  for (int i = 0; i < 16; ++i) M(i / 4, i % 4) = v[static_cast<size_t>(i)];
  if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) throw std::runtime_error(where + ": last row must be 0 0 0 1");
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  if ((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-4 || R.determinant() < 0)
    throw std::runtime_error(where + ": the rotation part is not a rotation");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  T.translation() = M.topRightCorner<3, 1>();
  return T;
}

int run_register(const RegisterOptions& o) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  const Scan source = read_scan(o.source);
  Scan target = read_scan(o.target);
  spdlog::info("read {} ({} points) and {} ({} points) in {:.0f} ms", o.source, source.cloud.size(), o.target,
               target.cloud.size(), std::chrono::duration<double, std::milli>(clock::now() - t0).count());

  Eigen::Isometry3d T_initial = Eigen::Isometry3d::Identity();
  if (!o.init.empty()) {
    T_initial = parse_matrix(o.init, "--init");
  } else if (!o.init_file.empty()) {
    std::ifstream in(o.init_file);
    if (!in) throw std::runtime_error(o.init_file + ": cannot open: " + std::strerror(errno));
    std::ostringstream s;
    s << in.rdbuf();
    T_initial = parse_matrix(s.str(), o.init_file);
  } else if (source.T_world_scan && target.T_world_scan) {
    T_initial = target.T_world_scan->inverse() * *source.T_world_scan;
    spdlog::info("initial guess from the scans' poses");
  }

  // The pyramid's finest level pairs point to plane unless told; one plain
  // ICP point to point, as PCL's and Open3D's do.
  const IcpMetric metric = (o.metric_given ? o.metric == "plane" : !o.plain) ? IcpMetric::PointToPlane
                                                                            : IcpMetric::PointToPoint;
  const auto ti = clock::now();
  Eigen::Isometry3d T;
  double rmse = 0.0, inliers = 0.0;
  int iterations = 0;
  std::string failure;
  if (o.plain) {
    IcpSettings s;
    s.metric = metric;
    s.max_iterations = o.iterations;
    s.max_correspondence_m = o.max_dist_m;
    s.min_correspondence_m = o.min_dist_m;
    s.huber_m = o.huber_m;
    s.threads = o.threads;
    s.exact_neighbours = o.exact;
    s.coarse_stride = o.coarse_stride;
    if (s.metric == IcpMetric::PointToPlane && target.cloud.normals.size() != target.cloud.size()) {
      const auto tn = clock::now();
      estimate_normals(target.cloud, 10);
      spdlog::info("estimated target normals in {:.0f} ms", std::chrono::duration<double, std::milli>(clock::now() - tn).count());
    }
    const IcpResult r = icp(source.cloud, target.cloud, T_initial, s);
    T = r.T_target_source;
    rmse = r.rmse_m;
    inliers = r.inlier_ratio;
    iterations = r.iterations;
    failure = icp_failure(r, o.min_inlier_ratio);
  } else {
    RegistrationSettings s;
    s.fine_metric = metric;
    s.fine_voxel_m = o.voxel_m;
    s.coarse_voxel_m = o.coarse_voxel_m;
    s.min_inlier_ratio = o.min_inlier_ratio;
    s.threads = o.threads;
    const RegistrationResult r = register_clouds(source.cloud, target.cloud, T_initial, s);
    for (const auto& l : r.levels)
      spdlog::info("level {:.3g} m: {} onto {} points, pairing {:.3g} m, {} iterations in {:.1f} ms, rmse {:.4f} m, {:.0f} % paired{}",
                   l.voxel_m, l.source_points, l.target_points, l.pairing_m, l.icp.iterations, 1e3 * l.seconds,
                   l.icp.rmse_m, 100.0 * l.icp.inlier_ratio, l.icp.converged ? ", converged" : "");
    spdlog::info("pyramid sized, filtered and target normals estimated in {:.1f} ms; the answer from {}", 1e3 * r.prepare_s,
                 r.from_start ? "the finer levels run from the start" : "the whole pyramid");
    T = r.T_target_source;
    rmse = r.rmse_m;
    inliers = r.inlier_ratio;
    iterations = r.iterations;
    failure = r.failure;
  }
  spdlog::info("registration: {} iterations in {:.1f} ms", iterations,
               std::chrono::duration<double, std::milli>(clock::now() - ti).count());
  if (!failure.empty()) {
    // Never a transform that looks like an answer: nothing on stdout.
    spdlog::error("{} onto {}: {} (rmse {:.4f} m, {:.0f} % paired)", o.source, o.target, failure, rmse, 100.0 * inliers);
    return 1;
  }
  const Eigen::Matrix4d M = T.matrix();
  for (int i = 0; i < 4; ++i)
    std::printf("%.9g %.9g %.9g %.9g\n", M(i, 0), M(i, 1), M(i, 2), M(i, 3));
  std::printf("rmse_m %.9g\niterations %d\ninlier_ratio %.6f\nconverged true\n", rmse, iterations, inliers);
  return 0;
}

}  // namespace

void add_register_command(CLI::App& app) {
  auto o = std::make_shared<RegisterOptions>();
  CLI::App* cmd = app.add_subcommand("register", "ICP: print the 4x4 transform that maps SOURCE onto TARGET, then rmse and iterations");
  // No CLI::ExistingFile: the readers name the file and the OS's reason.
  cmd->add_option("SOURCE", o->source, "cloud to move (.pcd .ply .xyz .3d .vtk .bt .ot)")->required();
  cmd->add_option("TARGET", o->target, "cloud to align to")->required();
  auto* init = cmd->add_option("--init", o->init, "initial guess: 16 numbers, row-major (default: from the scans' poses, else identity)");
  cmd->add_option("--init-file", o->init_file, "initial guess from a file of 16 numbers, row-major")->excludes(init);
  auto* metric = cmd->add_option("--metric", o->metric, "point (point-to-point) or plane (point-to-plane): the pyramid's finest level (default plane), or the one ICP's (default point)")
      ->check(CLI::IsMember({"point", "plane"}));
  cmd->add_option("--voxel", o->voxel_m, "the pyramid's finest voxel, m (0: from the clouds)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_option("--coarse-voxel", o->coarse_voxel_m, "the pyramid's coarsest voxel, m (0: from the clouds)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--min-inliers", o->min_inlier_ratio, "not converged when a smaller share of the source is paired")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--threads", o->threads, "OpenMP threads (0: all)")->check(CLI::NonNegativeNumber)->capture_default_str();
  // One ICP as PCL and Open3D run it, at given pairing distances: any of these selects it.
  const char* kPlain = "One ICP instead of the pyramid (any of these options selects it)";
  std::vector<CLI::Option*> plain{
      cmd->add_option("--iterations", o->iterations, "at most this many iterations")->check(CLI::PositiveNumber)->capture_default_str(),
      cmd->add_option("--max-dist", o->max_dist_m, "first iteration's pairing distance, m")->check(CLI::PositiveNumber)->capture_default_str(),
      cmd->add_option("--min-dist", o->min_dist_m, "pairing distance it shrinks to, m")->check(CLI::PositiveNumber)->capture_default_str(),
      cmd->add_option("--huber", o->huber_m, "Huber kernel width, m (0: none)")->check(CLI::NonNegativeNumber)->capture_default_str(),
      cmd->add_flag("--exact", o->exact, "pair every point with its exact nearest neighbour (as PCL's and Open3D's k-d trees)"),
      cmd->add_option("--coarse-stride", o->coarse_stride,
                      "the first half of the iterations pairs every N-th source point, then halving to all (1: all points in every iteration, as PCL and Open3D)")
          ->check(CLI::PositiveNumber)
          ->capture_default_str()};
  for (auto* opt : plain) opt->group(kPlain);
  cmd->callback([o, plain, metric]() {
    if (o->min_dist_m > o->max_dist_m) throw CLI::ValidationError("--min-dist", "must not exceed --max-dist");
    o->metric_given = metric->count() > 0;
    o->plain = std::any_of(plain.begin(), plain.end(), [](const CLI::Option* opt) { return opt->count() > 0; });
    int rc = 0;
    try {
      rc = run_register(*o);
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      rc = 2;  // bad input
    }
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace rise::semantic
