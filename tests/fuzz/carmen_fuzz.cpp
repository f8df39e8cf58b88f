// libFuzzer target: the CARMEN log reader on arbitrary text, then the grid
// its scans make. An error must be a std::runtime_error whose text starts
// with the file name; every scan read must have finite poses and ranges >= 0.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "semantic/occupancy_grid.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::vector<rise::semantic::LaserScan2D> scans;
  try {
    scans = rise::semantic::parse_carmen_log("fuzz.log", text);
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.log:"));
    return 0;
  }
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const auto& s : scans) {
    check(s.pose.allFinite());
    for (float r : s.ranges) check(std::isfinite(r) && r >= 0);
    lo = lo.cwiseMin(s.pose.head<2>());
    hi = hi.cwiseMax(s.pose.head<2>());
  }
  // Rasterise only what fits the fuzzer's memory (the grid refuses spans
  // over 1e8 cells itself, more than libFuzzer's 2 GB under ASan allows).
  if (!scans.empty() && (hi - lo).maxCoeff() < 200) {
    const auto g = rise::semantic::grid_from_scans(scans, 0.5);
    check(g.cells.size() == static_cast<size_t>(g.width) * static_cast<size_t>(g.height));
  }
  return 0;
}
