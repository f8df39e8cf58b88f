#include "semantic/octomap_format.hpp"

// The layout, as octomap 1.9 writes it (src/AbstractOcTree.cpp,
// AbstractOccupancyOcTree.cpp, OcTreeBaseImpl.hxx, OccupancyOcTreeBase.hxx):
//
//   # Octomap OcTree binary file        (.bt; .ot: "# Octomap OcTree file")
//   # (comments)
//   id ColorOcTree
//   size 1547112                        every node, the root included
//   res 0.02
//   data
//   <the tree, depth first from the root>
//
// .bt, per inner node two bytes; child i (0..7) has the two bits at 2·(i mod
// 4) of byte i / 4: 00 none (unknown space), 01 free leaf, 10 occupied
// leaf, 11 inner node, whose own two bytes follow after this node's, in
// child order. E.g. 0x09 0x00: child 0 free, child 1 occupied, 2..7 none.
// .ot, per node its payload (log-odds as a little-endian float; ColorOcTree
// then r g b) and a byte whose bit i says child i follows, depth first.
//
// Child i's cube is the parent's half along x when bit 0 of i is set, along
// y for bit 1, z for bit 2. Keys are 16 bit, key 32768 is coordinate 0, so a
// cell's centre is (key − 32768 + 0.5) · res.

#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "semantic/cloud_formats.hpp"

namespace rise::semantic {
namespace formats {
namespace {

constexpr int kTreeDepth = 16;
constexpr uint32_t kKeyOfZero = 32768;

using Key = std::array<uint32_t, 3>;  // the cube's lowest cell

enum class Kind { Binary, Full };

struct Header {
  Kind kind = Kind::Binary;
  std::string id;
  uint64_t size = 0;
  double resolution_m = 0;
  size_t data_at = 0;
  size_t id_line = 0, size_line = 0;
};

// As AbstractOcTree::readHeader, but every problem is an error with its
// line: unknown keys (octomap warns and skips them), repeats, missing keys.
Header parse_header(const std::string& path, std::string_view bytes) {
  static constexpr std::string_view kBinary = "# Octomap OcTree binary file", kFull = "# Octomap OcTree file";
  Lines lines{bytes};
  std::string_view line;
  Header h;
  if (!lines.next(line) || !(line.starts_with(kBinary) || line.starts_with(kFull)))
    fail_line(path, 1, "not an OctoMap file: the first line is neither '" + std::string(kBinary) + "' nor '" +
                           std::string(kFull) + "'");
  h.kind = line.starts_with(kBinary) ? Kind::Binary : Kind::Full;
  std::map<std::string, size_t> line_of;
  bool data = false;
  while (!data && lines.next(line)) {
    const auto w = words(line);
    if (w.empty() || w[0].front() == '#') continue;
    const std::string key(w[0]);
    const size_t n = lines.number;
    if (line_of.count(key)) fail_line(path, n, key + ": given twice (first on line " + std::to_string(line_of[key]) + ")");
    line_of[key] = n;
    if (key == "data") {
      if (w.size() != 1) fail_line(path, n, "data: expected nothing after it on its line");
      data = true;
      h.data_at = std::min(lines.pos, bytes.size());
      continue;
    }
    if (w.size() != 2) fail_line(path, n, key + ": expected one value");
    if (key == "id") {
      h.id = std::string(w[1]);
      h.id_line = n;
    } else if (key == "size") {
      h.size = number<uint64_t>(w[1], path, n, key);
      h.size_line = n;
    } else if (key == "res") {
      h.resolution_m = number<double>(w[1], path, n, key);
      if (!(h.resolution_m > 0) || !std::isfinite(h.resolution_m)) fail_line(path, n, "res: must be a positive number");
    } else {
      fail_line(path, n, "unknown header key '" + key + "' (expected id, size, res, data)");
    }
  }
  const size_t n = lines.number;
  if (!data) fail_line(path, n, "data: missing (the file ends in the header)");
  for (const char* key : {"id", "size", "res"})
    if (!line_of.count(key)) fail_line(path, n, std::string(key) + ": missing");
  if (h.id == "1") h.id = "OcTree";  // octomap's deprecated id, as its readHeader maps it
  return h;
}

// The bytes of a node's payload in an .ot (OcTreeDataNode::writeData and
// its overrides); 0 for an id whose nodes are not occupancy.
size_t payload_bytes(const std::string& id) {
  if (id == "OcTree") return 4;  // float log-odds
  // octomap 1.9's OcTreeNodeStamped does not override writeData: its
  // timestamp is not saved, the payload is the log-odds alone.
  if (id == "OcTreeStamped") return 4;
  if (id == "ColorOcTree") return 7;  // float log-odds, then r g b
  return 0;
}

struct TreeReader {
  const std::string& path;
  std::string_view bytes;
  size_t pos;
  double resolution_m;
  size_t payload;
  OctoMap& map;

  void need(size_t n) const {
    if (bytes.size() - pos < n)
      fail_byte(path, pos, "tree data truncated: a node needs " + std::to_string(n) + " bytes, " +
                               std::to_string(bytes.size() - pos) + " left");
  }

  static Key child(const Key& k, int depth, unsigned i) {
    const uint32_t half = (uint32_t{1} << kTreeDepth) >> (depth + 1);
    return {k[0] + ((i & 1) ? half : 0), k[1] + ((i & 2) ? half : 0), k[2] + ((i & 4) ? half : 0)};
  }

  void leaf(const Key& k, int depth, bool occupied, std::optional<float> log_odds) {
    const double cells = static_cast<double>(uint32_t{1} << (kTreeDepth - depth));
    OctoMapLeaf l;
    for (int a = 0; a < 3; ++a)
      l.centre_m[a] = (static_cast<double>(k[static_cast<size_t>(a)]) - kKeyOfZero + 0.5 * cells) * resolution_m;
    l.size_m = cells * resolution_m;
    l.depth = depth;
    l.occupied = occupied;
    l.log_odds = log_odds;
    map.leaves.push_back(l);
    if (occupied) {
      const uint64_t add = uint64_t{1} << (3 * (kTreeDepth - depth));
      map.occupied_cells = map.occupied_cells > std::numeric_limits<uint64_t>::max() - add
                               ? std::numeric_limits<uint64_t>::max()
                               : map.occupied_cells + add;
    }
  }

  void deeper_than_16(size_t at) const {
    fail_byte(path, at, "a node at depth " + std::to_string(kTreeDepth) + " has children: the tree is deeper than " +
                            std::to_string(kTreeDepth) + " levels");
  }

  // OccupancyOcTreeBase::readBinaryNode: leaves first, then the inner
  // children's subtrees in child order.
  void binary_node(const Key& k, int depth) {
    need(2);
    const size_t at = pos;
    const unsigned codes = static_cast<unsigned char>(bytes[pos]) | static_cast<unsigned>(static_cast<unsigned char>(bytes[pos + 1])) << 8;
    pos += 2;
    ++map.inner_nodes;
    if (codes == 0) fail_byte(path, at, "an inner node without children");
    for (unsigned i = 0; i < 8; ++i) {
      const unsigned code = (codes >> (2 * i)) & 3;
      if (code == 1 || code == 2) leaf(child(k, depth, i), depth + 1, code == 2, std::nullopt);
      if (code == 3 && depth + 1 == kTreeDepth) deeper_than_16(at);
    }
    for (unsigned i = 0; i < 8; ++i)
      if (((codes >> (2 * i)) & 3) == 3) binary_node(child(k, depth, i), depth + 1);
  }

  // OcTreeBaseImpl::readNodesRecurs.
  void full_node(const Key& k, int depth) {
    need(payload + 1);
    uint32_t u = 0;
    for (size_t b = 0; b < 4; ++b) u |= static_cast<uint32_t>(static_cast<unsigned char>(bytes[pos + b])) << (8 * b);
    const float log_odds = std::bit_cast<float>(u);
    pos += payload;
    const auto children = static_cast<unsigned char>(bytes[pos]);
    ++pos;
    if (children == 0) {
      // isNodeOccupied: log-odds ≥ the threshold, 0 (p = 0.5) by default;
      // the file does not keep the tree's threshold.
      leaf(k, depth, log_odds >= 0.0f, log_odds);
      return;
    }
    if (depth == kTreeDepth) deeper_than_16(pos - 1);
    ++map.inner_nodes;
    for (unsigned i = 0; i < 8; ++i)
      if (children & (1u << i)) full_node(child(k, depth, i), depth + 1);
  }
};

}  // namespace

OctoMap parse_octomap(const std::string& path, std::string_view bytes) {
  const Header h = parse_header(path, bytes);
  OctoMap map;
  map.tree_type = h.id;
  map.resolution_m = h.resolution_m;
  static const char* known = "OcTree, ColorOcTree, OcTreeStamped";
  if (payload_bytes(h.id) == 0)
    fail_line(path, h.id_line, "id: '" + h.id + "' is not an occupancy tree this reader knows (" + known + ")");
  TreeReader r{path, bytes, h.data_at, h.resolution_m, payload_bytes(h.id), map};
  if (h.size > 0) {
    if (h.kind == Kind::Binary) r.binary_node({0, 0, 0}, 0);
    else r.full_node({0, 0, 0}, 0);
  }
  map.nodes = map.inner_nodes + map.leaves.size();
  if (map.nodes != h.size)
    fail_line(path, h.size_line, "size: " + std::to_string(h.size) + " nodes announced, the tree has " +
                                     std::to_string(map.nodes));
  if (r.pos != bytes.size())
    fail_byte(path, r.pos, std::to_string(bytes.size() - r.pos) + " bytes after the end of the tree");
  return map;
}

Cloud octomap_cloud(const std::string& path, std::string_view bytes, uint64_t max_points) {
  const OctoMap map = parse_octomap(path, bytes);
  if (map.occupied_cells > max_points) {
    std::ostringstream m;
    m << path << ": " << map.occupied_cells << " occupied cells of " << map.resolution_m << " m, more than the "
      << max_points << " points a cloud may have";
    throw std::runtime_error(m.str());
  }
  return occupied_voxels(map);
}

}  // namespace formats

OctoMap read_octomap(const std::string& path) { return formats::parse_octomap(path, formats::read_file(path)); }

Cloud occupied_voxels(const OctoMap& map) {
  Cloud cloud;
  cloud.points.reserve(map.occupied_cells);
  for (const auto& l : map.leaves) {
    if (!l.occupied) continue;
    const int n = 1 << (formats::kTreeDepth - l.depth);
    const Eigen::Vector3d first = l.centre_m - Eigen::Vector3d::Constant(0.5 * l.size_m - 0.5 * map.resolution_m);
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          cloud.points.push_back((first + map.resolution_m * Eigen::Vector3d(x, y, z)).cast<float>());
  }
  return cloud;
}

}  // namespace rise::semantic
