// Runs the built rise-semantic program, as a user would.

#include <catch2/catch.hpp>

#include "tests/test_data.hpp"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>

namespace {

using rise::test::data_file;

struct Run {
  int status = -1;
  std::string out;
};

Run run(const std::string& args) {
  const std::string cmd = std::string(RISE_BINARY_DIR) + "/bin/rise-semantic " + args + " 2>/dev/null";
  Run r;
  FILE* p = ::popen(cmd.c_str(), "r");
  REQUIRE(p != nullptr);
  std::array<char, 4096> buf{};
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  r.status = ::pclose(p);
  return r;
}

}  // namespace

TEST_CASE("rise-semantic register prints PCL's bunny transform, rmse and iterations", "[semantic]") {
  const std::string bun0 = data_file("pointclouds/pcl/bun0.pcd"), bun4 = data_file("pointclouds/pcl/bun4.pcd");
  if (bun0.empty() || bun4.empty()) {
    WARN("skipped: RISE_TEST_DATA/pointclouds/pcl/bun0.pcd, bun4.pcd not found");
    return;
  }
  const Run r = run("register " + bun0 + " " + bun4 + " --max-dist 0.05 --min-dist 0.05 --iterations 50 --threads 1 --exact --coarse-stride 1");
  REQUIRE(r.status == 0);
  std::istringstream in(r.out);
  double T[4][4];
  for (auto& row : T)
    for (double& v : row) REQUIRE(in >> v);
  const double expected[3][4] = {{0.8806, 0.0365, -0.4724, 0.03453},
                                 {-0.02354, 0.9992, 0.03326, -0.001519},
                                 {0.4732, -0.01817, 0.8808, 0.04116}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) CHECK(T[i][j] == Approx(expected[i][j]).margin(i == 0 && j == 1 ? 1e-2 : 1e-3));
  CHECK(T[3][3] == 1.0);
  std::string key;
  double rmse = -1;
  int iterations = -1;
  REQUIRE(in >> key >> rmse);
  CHECK(key == "rmse_m");
  CHECK(rmse < 0.01);
  REQUIRE(in >> key >> iterations);
  CHECK(key == "iterations");
  CHECK(iterations > 1);
  CHECK(iterations <= 50);
}

TEST_CASE("rise-semantic register refuses a bad initial guess and a bad file", "[semantic]") {
  const std::string bun0 = data_file("pointclouds/pcl/bun0.pcd");
  if (bun0.empty()) {
    WARN("skipped: RISE_TEST_DATA/pointclouds/pcl/bun0.pcd not found");
    return;
  }
  CHECK(run("register " + bun0 + " " + bun0 + " --init '1 0 0 0 0 1 0 0 0 0 1 0'").status != 0);
  CHECK(run("register " + bun0 + " " + bun0 + " --metric triangle").status != 0);
  const auto bad = std::filesystem::temp_directory_path() / "rise_register_bad.ply";
  { FILE* f = std::fopen(bad.c_str(), "w"); std::fputs("ply\nformat ascii 1.0\nelement vertex 5\n", f); std::fclose(f); }
  CHECK(run("register " + bad.string() + " " + bun0).status != 0);
  const auto init = std::filesystem::temp_directory_path() / "rise_register_init.txt";
  { FILE* f = std::fopen(init.c_str(), "w"); std::fputs("1 0 0 0.01\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", f); std::fclose(f); }
  const Run from_file = run("register " + bun0 + " " + bun0 + " --init-file " + init.string() + " --exact");
  CHECK(from_file.status == 0);
  CHECK(from_file.out.find("converged true") != std::string::npos);
  CHECK(run("register " + bun0 + " " + bun0 + " --init-file " + init.string() + " --init '1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1'").status != 0);
  // The identity guess given explicitly still aligns.
  const Run ok = run("register " + bun0 + " " + bun0 + " --init '1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1'");
  CHECK(ok.status == 0);
  CHECK(ok.out.find("converged true") != std::string::npos);
}
