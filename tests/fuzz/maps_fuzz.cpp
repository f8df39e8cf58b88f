// libFuzzer target: the 3D map readers — OctoMap .bt/.ot (header, tree,
// coarse leaves expanded to cells) and legacy VTK (ASCII and BINARY) — on
// arbitrary bytes. An error must be a std::runtime_error whose text starts
// with the file name; every point read must be finite, normals one per
// point, and an OctoMap's counts must agree with its leaves.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "semantic/cloud_formats.hpp"
#include "semantic/octomap_format.hpp"

namespace sem = rise::semantic;
namespace fmt = rise::semantic::formats;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

void check_cloud(const sem::Cloud& c) {
  check(c.normals.empty() || c.normals.size() == c.points.size());
  for (const auto& p : c.points) check(p.allFinite());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const sem::OctoMap m = fmt::parse_octomap("fuzz.bt", bytes);
    check(m.nodes == m.inner_nodes + m.leaves.size());
    // Depth 0: a root without children (.ot), one leaf over the whole tree.
    for (const auto& l : m.leaves) check(l.depth >= 0 && l.depth <= 16 && l.size_m > 0);
    // Few enough cells to expand in a fuzzer's memory.
    if (m.occupied_cells <= 100000) check(sem::occupied_voxels(m).size() == m.occupied_cells);
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.bt"));
  }
  try {
    check_cloud(fmt::octomap_cloud("fuzz.ot", bytes, 100000));
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.ot"));
  }
  try {
    check_cloud(fmt::parse_vtk("fuzz.vtk", bytes));
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.vtk"));
  }
  return 0;
}
