#pragma once

// Triangle meshes from STL (binary or ASCII) and COLLADA (.dae) files,
// through Debian's libassimp (COLLADA checked and rewritten first, with
// libxml2): a URDF link's mesh collision and visual shapes.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace rise::sim {

struct TriangleMesh {
  std::vector<float> vertices_m;    ///< x, y, z per vertex
  std::vector<uint32_t> triangles;  ///< three vertex indices per triangle, counter-clockwise seen from outside

  bool operator==(const TriangleMesh&) const = default;
  std::size_t vertex_count() const { return vertices_m.size() / 3; }
  std::size_t triangle_count() const { return triangles.size() / 3; }
};

constexpr std::size_t kMaxMeshTriangles = 200000;

/// Reads every mesh of the file at `path` into one, with its nodes'
/// transforms applied (COLLADA's unit and up axis included: the result is in
/// metres, z up), then scaled per axis by `scale`. A COLLADA file is read
/// through plain_collada (sim/collada_geometry.hpp): assimp sees only its
/// checked geometry. Throws std::runtime_error "<path>: <assimp's message>"
/// for a file assimp cannot read, "<path>:<line>: ..." for a COLLADA file
/// plain_collada refuses, and "<path>: ..." for one without triangles, more
/// than kMaxMeshTriangles triangles or a coordinate that is not finite. Not
/// for the cyclic path.
TriangleMesh read_mesh_file(const std::string& path, const std::array<double, 3>& scale = {1, 1, 1});

/// The same from a file's bytes; `hint` is its extension ("stl", "dae").
TriangleMesh parse_mesh(const std::string& bytes, const std::string& hint,
                        const std::array<double, 3>& scale = {1, 1, 1});

/// Binary STL of `mesh` (80-byte header, count, 50 bytes per triangle).
std::string binary_stl(const TriangleMesh& mesh);

}  // namespace rise::sim
