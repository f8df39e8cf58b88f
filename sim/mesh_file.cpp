#include "sim/mesh_file.hpp"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "sim/collada_geometry.hpp"

namespace rise::sim {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

// Appends node's meshes (and its children's) with their accumulated transform.
void collect(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent, const std::array<double, 3>& scale,
             TriangleMesh& out, const std::string& where) {
  const aiMatrix4x4 T = parent * node.mTransformation;
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const aiMesh& m = *scene.mMeshes[node.mMeshes[k]];
    const auto base = static_cast<uint32_t>(out.vertex_count());
    for (unsigned v = 0; v < m.mNumVertices; ++v) {
      const aiVector3D p = T * m.mVertices[v];
      const double xyz[3] = {p.x * scale[0], p.y * scale[1], p.z * scale[2]};
      for (double c : xyz) {
        // Scaled, a finite float can leave float's range: test what is stored.
        const auto f = static_cast<float>(c);
        if (!std::isfinite(f)) fail(where + ": a vertex coordinate is not finite");
        out.vertices_m.push_back(f);
      }
    }
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
      const aiFace& face = m.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines left by triangulation
      for (unsigned i = 0; i < 3; ++i) out.triangles.push_back(base + face.mIndices[i]);
      if (out.triangle_count() > kMaxMeshTriangles)
        fail(where + ": more than " + std::to_string(kMaxMeshTriangles) + " triangles");
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) collect(scene, *node.mChildren[c], T, scale, out, where);
}

TriangleMesh from_scene(const aiScene* scene, const Assimp::Importer& importer, const std::array<double, 3>& scale,
                        const std::string& where) {
  if (!scene || !scene->mRootNode) fail(where + ": " + importer.GetErrorString());
  for (double s : scale)
    if (!(std::isfinite(s) && s != 0.0)) fail(where + ": scale must be finite and not 0");
  TriangleMesh out;
  collect(*scene, *scene->mRootNode, aiMatrix4x4(), scale, out, where);
  if (out.triangles.empty()) fail(where + ": no triangles");
  // A mirroring scale turns the faces inside out: restore their winding.
  if (scale[0] * scale[1] * scale[2] < 0)
    for (std::size_t t = 0; t < out.triangles.size(); t += 3) std::swap(out.triangles[t + 1], out.triangles[t + 2]);
  return out;
}

bool looks_like_collada(const std::string& bytes, const std::string& hint) {
  if (hint == "dae" || hint == "DAE") return true;
  if (hint == "stl" || hint == "STL") return false;
  std::string lower = bytes.substr(0, std::min<std::size_t>(bytes.size(), 4096));
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower.find("collada") != std::string::npos;
}

TriangleMesh read(const std::string& bytes, const std::string& hint, const std::array<double, 3>& scale,
                  const std::string& where);

// Triangles only, shared vertices merged; no normals, no materials (the
// simulator and the browser's flat shading need neither).
constexpr unsigned kFlags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                            aiProcess_FindInvalidData | aiProcess_ValidateDataStructure;

// An STL is ASCII ("solid ...") or binary: 80 bytes, a count, 50 bytes per
// triangle. Checked here so that assimp never guesses another format for it.
void check_stl(const std::string& bytes, const std::string& where) {
  if (bytes.rfind("solid", 0) == 0) return;
  uint32_t count = 0;
  if (bytes.size() >= 84) std::memcpy(&count, bytes.data() + 80, 4);
  if (bytes.size() < 84 || bytes.size() != 84 + 50 * static_cast<uint64_t>(count))
    fail(where + ": not an STL (neither \"solid\" text nor 84 + 50 x its triangle count bytes)");
}

TriangleMesh read(const std::string& bytes, const std::string& hint, const std::array<double, 3>& scale,
                  const std::string& where) {
  Assimp::Importer importer;
  if (hint == "stl" || hint == "STL") check_stl(bytes, where);
  else if (looks_like_collada(bytes, hint)) {
    // assimp reads our plain rewrite of its geometry, never the file itself.
    const std::string plain = plain_collada(bytes, where);
    return from_scene(importer.ReadFileFromMemory(plain.data(), plain.size(), kFlags, "dae"), importer, scale, where);
  }
  return from_scene(importer.ReadFileFromMemory(bytes.data(), bytes.size(), kFlags, hint.c_str()), importer, scale,
                    where);
}

}  // namespace

TriangleMesh read_mesh_file(const std::string& path, const std::array<double, 3>& scale) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream bytes;
  bytes << in.rdbuf();
  const std::string ext = std::filesystem::path(path).extension().string();
  return read(bytes.str(), ext.empty() ? "" : ext.substr(1), scale, path);
}

TriangleMesh parse_mesh(const std::string& bytes, const std::string& hint, const std::array<double, 3>& scale) {
  return read(bytes, hint, scale, "mesh");
}

std::string binary_stl(const TriangleMesh& mesh) {
  std::string out(80, '\0');
  const std::string header = "rise binary STL";
  out.replace(0, header.size(), header);
  const auto put = [&out](const void* p, std::size_t n) { out.append(static_cast<const char*>(p), n); };
  const auto count = static_cast<uint32_t>(mesh.triangle_count());
  put(&count, 4);  // STL is little-endian, as is every machine this builds for
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    float v[3][3];
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) v[i][k] = mesh.vertices_m[3 * mesh.triangles[t + i] + k];
    const float a[3] = {v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]};
    const float b[3] = {v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]};
    float n[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (float& c : n) c = len > 0 ? c / len : 0.0f;
    put(n, 12);
    put(v, 36);
    const uint16_t attributes = 0;
    put(&attributes, 2);
  }
  return out;
}

}  // namespace rise::sim
