#include "sim/odometry.hpp"

#include <cmath>

namespace rise::sim {

Odometry::Odometry(const OdometryDescription& description, double gauge_m, std::array<double, 2> start_m,
                   double start_yaw_rad, uint64_t seed)
    : d_(description), gauge_m_(gauge_m), rng_(seed) {
  for (double& s : scale_) s = 1.0 + d_.scale_sigma * normal_(rng_);
  reading_.position_m = start_m;
  reading_.yaw_rad = start_yaw_rad;
}

void Odometry::update(double left_mps, double right_mps, double dt_s) {
  std::array<double, 2> travel_m{left_mps * dt_s, right_mps * dt_s};
  for (std::size_t i = 0; i < 2; ++i) {
    travel_m[i] *= scale_[i];
    // White noise whose variance grows with the distance: σ·√|travel| per step.
    if (d_.noise_per_sqrt_m > 0.0) travel_m[i] += d_.noise_per_sqrt_m * std::sqrt(std::fabs(travel_m[i])) * normal_(rng_);
  }
  const double ds = (travel_m[0] + travel_m[1]) / 2;
  const double dyaw = (travel_m[1] - travel_m[0]) / gauge_m_;
  const double mid = reading_.yaw_rad + dyaw / 2;
  reading_.position_m[0] += ds * std::cos(mid);
  reading_.position_m[1] += ds * std::sin(mid);
  reading_.yaw_rad = std::remainder(reading_.yaw_rad + dyaw, 2 * M_PI);
  reading_.linear_mps = dt_s > 0 ? ds / dt_s : 0.0;
  reading_.angular_radps = dt_s > 0 ? dyaw / dt_s : 0.0;
  reading_.distance_m += std::fabs(ds);
}

}  // namespace rise::sim
