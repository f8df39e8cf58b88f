#include "sim/imu.hpp"

namespace rise::sim {

Imu::Imu(const ImuDescription& description, const Eigen::Vector3d& gravity_world_mps2, uint64_t seed)
    : d_(description), gravity_world_(gravity_world_mps2), rng_(seed) {
  for (double& b : gyro_bias_) b = d_.gyro_bias_radps * normal_(rng_);
  for (double& b : accel_bias_) b = d_.accel_bias_mps2 * normal_(rng_);
}

void Imu::update(const Eigen::Matrix3d& R_world_base, const Eigen::Vector3d& velocity_world_mps,
                 const Eigen::Vector3d& angular_velocity_base_radps, double dt_s) {
  const Eigen::Vector3d accel_world =
      first_ || dt_s <= 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d((velocity_world_mps - last_velocity_world_) / dt_s);
  last_velocity_world_ = velocity_world_mps;
  first_ = false;
  const Eigen::Vector3d specific_base = R_world_base.transpose() * (accel_world - gravity_world_);
  for (Eigen::Index k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    reading_.angular_velocity_radps[i] =
        angular_velocity_base_radps[k] + gyro_bias_[i] + d_.gyro_noise_radps * normal_(rng_);
    reading_.linear_acceleration_mps2[i] = specific_base[k] + accel_bias_[i] + d_.accel_noise_mps2 * normal_(rng_);
  }
}

}  // namespace rise::sim
