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
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

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

// assimp 5.2's COLLADA reader misreads an index list with a non-digit in it
// and asks for gigabytes (found by the mesh fuzz target): the index lists
// (<p>, <v>, <vcount>) must be digits and white space before it sees them.
void check_collada_indices(const std::string& text, const std::string& where) {
  for (const std::string tag : {"p", "v", "vcount"}) {
    const std::string open = "<" + tag, close = "</" + tag + ">";
    for (std::size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
      const std::size_t after = at + open.size();
      if (after >= text.size()) break;
      const char c = text[after];
      if (c != '>' && !std::isspace(static_cast<unsigned char>(c))) continue;  // another element: <param>, <vertices>
      const std::size_t start = text.find('>', after);
      if (start == std::string::npos) break;
      if (text[start - 1] == '/') continue;  // empty: <p/>
      const std::size_t end = text.find(close, start);
      if (end == std::string::npos) fail(where + ": <" + tag + "> without </" + tag + ">");
      // XML's white space only: assimp splits on these, not on \v or \f
      // (a \v between indices made it ask for 2.4 GB, the fuzz target found).
      for (std::size_t i = start + 1; i < end; ++i)
        if (!std::isdigit(static_cast<unsigned char>(text[i])) && std::string_view(" \t\n\r").find(text[i]) == std::string_view::npos)
          fail(where + ": <" + tag + "> holds a non-digit (an index list is digits and white space)");
    }
  }
}

// ... and it follows a null pointer for an array or a primitive list without
// its count (the fuzz target's next find): each must carry count="digits".
void check_collada_counts(const std::string& text, const std::string& where) {
  for (const std::string tag : {"float_array", "int_array", "accessor", "triangles", "polylist", "polygons", "tristrips",
                                "trifans", "lines", "linestrips"}) {
    const std::string open = "<" + tag;
    for (std::size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
      const std::size_t after = at + open.size();
      if (after >= text.size()) break;
      if (text[after] != '>' && text[after] != '/' && !std::isspace(static_cast<unsigned char>(text[after]))) continue;
      const std::size_t end = text.find('>', after);
      if (end == std::string::npos) fail(where + ": <" + tag + " without its '>'");
      const std::string attrs = text.substr(after, end - after);
      std::size_t c = std::string::npos;
      for (const char* key : {" count=\"", "\tcount=\"", "\ncount=\""})
        if (c == std::string::npos) c = attrs.find(key);
      bool ok = c != std::string::npos;
      if (ok) {
        std::size_t i = c + 8, digits = 0;
        while (i < attrs.size() && std::isdigit(static_cast<unsigned char>(attrs[i]))) ++i, ++digits;
        ok = digits > 0 && digits <= 9 && i < attrs.size() && attrs[i] == '"';
      }
      if (!ok) fail(where + ": <" + tag + "> needs count=\"N\"");
    }
  }
}

// The integers of the element `tag` (its first, within [from, to)), or
// nullopt when there is none; check_collada_indices has made them digits.
std::optional<std::vector<uint64_t>> numbers_in(const std::string& text, const std::string& tag, std::size_t from,
                                                std::size_t to) {
  const std::string open = "<" + tag + ">";
  const std::size_t at = text.find(open, from);
  if (at == std::string::npos || at >= to) return std::nullopt;
  const std::size_t end = text.find("</" + tag + ">", at);
  if (end == std::string::npos || end > to) return std::nullopt;
  std::vector<uint64_t> out;
  std::istringstream in(text.substr(at + open.size(), end - at - open.size()));
  std::string word;
  while (in >> word) out.push_back(word.size() > 9 ? UINT32_MAX : std::stoull(word));
  return out;
}

// ... and aborts (an ai_assert) when a primitive list's count does not
// match its indices: each <triangles count="N"> must hold 3 N vertices in
// its <p>, each <polylist count="N"> N <vcount>s and their sum in <p>, a
// vertex being one index per input offset. Other primitives are refused.
void check_collada_primitives(const std::string& text, const std::string& where) {
  for (const char* tag : {"polygons", "tristrips", "trifans", "lines", "linestrips"})
    if (text.find("<" + std::string(tag)) != std::string::npos)
      fail(where + ": <" + tag + ">: only <triangles> and <polylist> meshes are read");
  for (const std::string tag : {"triangles", "polylist"}) {
    const std::string open = "<" + tag;
    for (std::size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
      const std::size_t head_end = text.find('>', at);
      const std::size_t end = text.find("</" + tag + ">", at);
      if (head_end == std::string::npos || end == std::string::npos) fail(where + ": <" + tag + "> without its end");
      const std::string head = text.substr(at, head_end - at);
      const std::size_t c = head.find("count=\"");
      const uint64_t count = c == std::string::npos ? 0 : std::strtoull(head.c_str() + c + 7, nullptr, 10);
      // One index per distinct input offset.
      uint64_t stride = 1;
      for (std::size_t i = text.find("<input", at); i != std::string::npos && i < end; i = text.find("<input", i + 1)) {
        const std::size_t o = text.find("offset=\"", i);
        const std::size_t e = text.find('>', i);
        if (o != std::string::npos && o < e) stride = std::max<uint64_t>(stride, std::strtoull(text.c_str() + o + 8, nullptr, 10) + 1);
      }
      const auto p = numbers_in(text, "p", at, end);
      uint64_t vertices = 3 * count;
      if (tag == "polylist") {
        const auto v = numbers_in(text, "vcount", at, end);
        if (!v || v->size() != count) fail(where + ": <polylist count> does not match its <vcount>");
        vertices = 0;
        for (uint64_t n : *v) vertices += n;
      }
      if (!p || p->size() != vertices * stride)
        fail(where + ": <" + tag + " count=\"" + std::to_string(count) + "\"> does not match its <p>");
    }
  }
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
  if (hint == "stl" || hint == "STL") check_stl(bytes, where);
  else if (looks_like_collada(bytes, hint)) {
    check_collada_indices(bytes, where);
    check_collada_counts(bytes, where);
    check_collada_primitives(bytes, where);
  }
  Assimp::Importer importer;
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
