// libFuzzer target: a URDF's STL mesh file (sim/mesh_file.hpp): the bytes
// through our STL check and libassimp, then our checks. An error must be a
// std::runtime_error; a mesh taken must be triangles whose indices name its
// vertices and whose coordinates are finite. With bit 0 of the first byte
// set, COLLADA instead: by hand only (RISE_FUZZ_COLLADA=1), since assimp
// 5.2's COLLADA reader still aborts on some malformed files (an ai_assert
// on a primitive count) past the checks mesh_file.cpp adds.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "sim/mesh_file.hpp"
#include "tests/fuzz/fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  static const bool collada = std::getenv("RISE_FUZZ_COLLADA") != nullptr;
  const char* hint = collada && (data[0] & 1) ? "dae" : "stl";
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
