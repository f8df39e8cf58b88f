#include <catch2/catch.hpp>

#include <cmath>

#include "sim/imu.hpp"
#include "sim/odometry.hpp"
#include "sim/simulation.hpp"
#include "tests/sim/sim_panel.hpp"

using namespace rise::sim;
using rise::sim::testing::drive_panel;
using rise::sim::testing::run_for;

namespace {
const std::string kTracked = std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml";
const std::string kSkid = std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml";

double odometry_error_m(const RobotSnapshot& s) {
  return std::hypot(s.odometry.position_m[0] - s.position_m[0], s.odometry.position_m[1] - s.position_m[1]);
}
}  // namespace

TEST_CASE("odometry without noise integrates a differential drive exactly", "[sim]") {
  Odometry odo(OdometryDescription{}, 0.5, {1.0, 2.0}, M_PI / 2, 1);
  for (int i = 0; i < 1000; ++i) odo.update(0.8, 0.8, 0.001);
  CHECK(odo.reading().position_m[0] == Approx(1.0).margin(1e-9));
  CHECK(odo.reading().position_m[1] == Approx(2.8).margin(1e-9));
  CHECK(odo.reading().distance_m == Approx(0.8).margin(1e-9));
  // Opposite sides: a spin in place at 2v/gauge.
  for (int i = 0; i < 1000; ++i) odo.update(-0.25, 0.25, 0.001);
  CHECK(odo.reading().angular_radps == Approx(1.0).margin(1e-9));
  CHECK(odo.reading().yaw_rad == Approx(M_PI / 2 + 1.0).margin(1e-9));
  CHECK(odo.reading().position_m[1] == Approx(2.8).margin(1e-9));
}

TEST_CASE("odometry equals the true pose on flat ground without noise and drifts with it", "[sim]") {
  const std::string file = GENERATE(kTracked, kSkid);
  INFO(file);
  auto quiet = load_robot_description(file);
  quiet.sensors.odometry = OdometryDescription{};
  Simulation exact(quiet, WorldDescription{});
  Simulation noisy(load_robot_description(file), WorldDescription{});
  double noisy_error_2s = 0.0;
  for (Simulation* sim : {&exact, &noisy}) {
    sim->set_input(drive_panel(1.0f, 0.0f));
    run_for(*sim, 2.0);
    if (sim == &noisy) noisy_error_2s = odometry_error_m(sim->snapshot());
    run_for(*sim, 4.0);
  }
  const auto e = exact.snapshot(), n = noisy.snapshot();
  REQUIRE(e.position_m[0] > 4.0);  // it drove several metres
  // Without noise: within 1 % of the distance and 0.5° over 5–7 m straight
  // (measured 0.6 % tracked, 0.7 % skid4: the belts' and tyres' slip).
  const double travelled = e.position_m[0];
  CHECK(odometry_error_m(e) < 0.01 * travelled);
  CHECK(std::fabs(std::remainder(e.odometry.yaw_rad - e.yaw_rad(), 2 * M_PI)) < 0.5 * M_PI / 180);
  CHECK(e.odometry.distance_m == Approx(travelled).epsilon(0.01));
  // With the robot file's noise (0.5 % scale σ per side, 1 cm/√m): several
  // centimetres off after 5–7 m, and more than after 2 s.
  INFO("noisy odometry error: " << noisy_error_2s << " m after 2 s, " << odometry_error_m(n) << " m after 6 s");
  CHECK(odometry_error_m(n) > 0.03);
  CHECK(odometry_error_m(n) > noisy_error_2s);
}

TEST_CASE("the IMU at rest reads gravity up and zero rate within its noise", "[sim]") {
  const bool noise = GENERATE(false, true);
  auto robot = load_robot_description(kTracked);
  if (!noise) robot.sensors.imu = ImuDescription{};
  const ImuDescription& d = robot.sensors.imu;
  Simulation sim(robot, WorldDescription{});
  run_for(sim, 1.0);  // settled on its tracks
  constexpr int kSamples = 1000;
  Eigen::Vector3d accel = Eigen::Vector3d::Zero(), rate = Eigen::Vector3d::Zero();
  double az2 = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    sim.step();
    const auto s = sim.snapshot();
    const Eigen::Vector3d a(s.imu.linear_acceleration_mps2.data());
    accel += a;
    az2 += a.z() * a.z();
    rate += Eigen::Vector3d(s.imu.angular_velocity_radps.data());
  }
  accel /= kSamples;
  rate /= kSamples;
  // Margins: 5 bias σ plus 5 σ/√n of the white noise plus 5 mm/s² / 1 mrad/s
  // of the settled robot's own jitter.
  const double accel_margin = 5 * d.accel_bias_mps2 + 5 * d.accel_noise_mps2 / std::sqrt(kSamples) + 0.005;
  const double rate_margin = 5 * d.gyro_bias_radps + 5 * d.gyro_noise_radps / std::sqrt(kSamples) + 0.001;
  INFO("mean accel " << accel.transpose() << ", mean rate " << rate.transpose());
  CHECK(accel.z() == Approx(9.81).margin(accel_margin));
  CHECK(accel.x() == Approx(0.0).margin(accel_margin));
  CHECK(accel.y() == Approx(0.0).margin(accel_margin));
  CHECK(rate.norm() < rate_margin * std::sqrt(3.0));
  const double sd = std::sqrt(az2 / kSamples - accel.z() * accel.z());
  if (noise) CHECK(sd == Approx(d.accel_noise_mps2).epsilon(0.2));
  else CHECK(sd < 0.005);
}

TEST_CASE("the IMU reads the specific force and rate of a tilted, accelerating body", "[sim]") {
  ImuDescription d;
  d.accel_noise_mps2 = 0.1;
  d.accel_bias_mps2 = 0.05;
  Imu imu(d, Eigen::Vector3d(0, 0, -9.81), 3);
  // Pitched 90° nose up (base x = world up), accelerating at 2 m/s² along world x.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY()).matrix();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  constexpr int kSamples = 4000;
  for (int i = 0; i <= kSamples; ++i) {
    imu.update(R, Eigen::Vector3d(2.0 * i * 0.001, 0, 0), Eigen::Vector3d(0, 0, 0.3), 0.001);
    if (i > 0) mean += Eigen::Vector3d(imu.reading().linear_acceleration_mps2.data());
    CHECK(imu.reading().angular_velocity_radps[2] == Approx(0.3).margin(1e-12));
  }
  mean /= kSamples;
  // World specific force (2, 0, 9.81) in the base frame: x = up, z = −world x.
  const Eigen::Vector3d bias(imu.accel_bias_mps2().data());
  const Eigen::Vector3d expected = Eigen::Vector3d(9.81, 0.0, -2.0) + bias;
  CHECK((mean - expected).norm() < 5 * 0.1 / std::sqrt(kSamples) * std::sqrt(3.0));
  CHECK(bias.norm() > 0.0);
}
