// libFuzzer target: a URDF's mesh file (sim/mesh_file.hpp): the bytes as
// STL, or as COLLADA with bit 0 of the first byte, through our checks and
// libassimp. An error must be a std::runtime_error; a mesh taken must be
// triangles whose indices name its vertices and whose coordinates are finite.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "sim/mesh_file.hpp"
#include "tests/fuzz/fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  const char* hint = data[0] & 1 ? "dae" : "stl";
  try {
    const auto mesh = rise::sim::parse_mesh(bytes, hint, {0.5, 1.0, -2.0});
    fuzz_check(mesh.vertices_m.size() % 3 == 0 && mesh.triangles.size() % 3 == 0);
    fuzz_check(!mesh.triangles.empty() && mesh.triangle_count() <= rise::sim::kMaxMeshTriangles);
    for (uint32_t i : mesh.triangles) fuzz_check(i < mesh.vertex_count());
    for (float v : mesh.vertices_m) fuzz_check(std::isfinite(v));
  } catch (const std::runtime_error& e) {
    fuzz_check(e.what()[0] != '\0');
  }
  return 0;
}
