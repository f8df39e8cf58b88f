#include "semantic/cloud_formats.hpp"

// The file formats without PCL: our PCD header check, PLY, XYZ, 3DTK's
// .3d/.pose/.frames and the simulator's .pose. Kept apart from PCL's heavy
// headers so that the fuzz targets build in seconds with clang's sanitizers.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "semantic/cloud_io.hpp"

namespace rise::semantic::formats {

std::string lower_extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

bool finite(const Eigen::Vector3f& p) { return p.allFinite(); }

// ---------------------------------------------------------------- PCD ----


// Our own pass over the header (pointclouds.org, "The PCD file format"):
// PCL's reader reports problems on its console without a line; this one
// names the line and the key, and sizes the data before PCL touches it.
PcdHeader parse_pcd_header(const std::string& path, std::string_view text) {
  PcdHeader h;
  Lines lines{text};
  std::string_view line;
  bool have_points = false;
  while (lines.next(line)) {
    const auto w = words(line);
    if (w.empty() || w[0].front() == '#') continue;
    const std::string key(w[0]);
    const size_t n = lines.number;
    if (h.line_of.count(key)) fail_line(path, n, key + ": given twice (first on line " + std::to_string(h.line_of[key]) + ")");
    h.line_of[key] = n;
    const auto ints = [&](std::vector<int>& out) {
      out.clear();
      for (size_t i = 1; i < w.size(); ++i) {
        const int v = number<int>(w[i], path, n, key);
        if (v < 1) fail_line(path, n, key + ": must be positive");
        out.push_back(v);
      }
    };
    if (key == "VERSION") {
    } else if (key == "FIELDS" || key == "COLUMNS") {
      h.fields.assign(w.begin() + 1, w.end());
      for (const auto& f : h.fields)
        if (!std::all_of(f.begin(), f.end(), [](unsigned char c) { return std::isalnum(c) || c == '_'; }))
          fail_line(path, n, key + ": field name '" + f + "' is not [A-Za-z0-9_]+");
    } else if (key == "SIZE") {
      ints(h.sizes);
      for (int s : h.sizes)
        if (s != 1 && s != 2 && s != 4 && s != 8) fail_line(path, n, "SIZE: must be 1, 2, 4 or 8");
    } else if (key == "TYPE") {
      h.types.clear();
      for (size_t i = 1; i < w.size(); ++i) {
        if (w[i].size() != 1 || std::string_view("FIU").find(w[i][0]) == std::string_view::npos)
          fail_line(path, n, "TYPE: must be F, I or U, not '" + std::string(w[i]) + "'");
        h.types.push_back(w[i][0]);
      }
    } else if (key == "COUNT") {
      ints(h.counts);
      // PCL's ascii reader sizes its buffers by the values a point has,
      // whatever the number of points (tests/fuzz/pcd_fuzz.cpp: COUNT
      // 1297379212 and no points asked it for 41 GB). The largest
      // descriptor PCL writes holds 640 (ESF).
      constexpr int kMaxCount = 1 << 16;
      for (int c : h.counts)
        if (c > kMaxCount)
          fail_line(path, n, "COUNT: " + std::to_string(c) + " values in one field, more than " +
                                 std::to_string(kMaxCount) + " (a descriptor has some hundreds)");
    } else if (key == "WIDTH") {
      if (w.size() != 2) fail_line(path, n, "WIDTH: expected one number");
      h.width = number<uint64_t>(w[1], path, n, key);
    } else if (key == "HEIGHT") {
      if (w.size() != 2) fail_line(path, n, "HEIGHT: expected one number");
      h.height = number<uint64_t>(w[1], path, n, key);
    } else if (key == "VIEWPOINT") {
      if (w.size() != 8) fail_line(path, n, "VIEWPOINT: expected 7 numbers");
      for (size_t i = 1; i < 8; ++i) {
        h.viewpoint[i - 1] = number<double>(w[i], path, n, key);
        if (!std::isfinite(h.viewpoint[i - 1])) fail_line(path, n, "VIEWPOINT: not finite");
      }
    } else if (key == "POINTS") {
      if (w.size() != 2) fail_line(path, n, "POINTS: expected one number");
      h.points = number<uint64_t>(w[1], path, n, key);
      have_points = true;
    } else if (key == "DATA") {
      if (w.size() != 2) fail_line(path, n, "DATA: expected ascii, binary or binary_compressed");
      h.data = std::string(w[1]);
      if (h.data != "ascii" && h.data != "binary" && h.data != "binary_compressed")
        fail_line(path, n, "DATA: expected ascii, binary or binary_compressed, not '" + h.data + "'");
      h.data_offset = lines.pos;
      h.data_line = n;
      break;
    } else {
      fail_line(path, n, "unknown header key '" + key + "'");
    }
  }
  const size_t n = lines.number;
  const auto at = [&](const char* key) { return h.line_of.count(key) ? h.line_of.at(key) : n; };
  if (h.data.empty()) fail_line(path, n, "DATA: missing (file ends in the header)");
  if (h.fields.empty()) fail_line(path, n, "FIELDS: missing");
  if (h.sizes.size() != h.fields.size()) fail_line(path, at("SIZE"), "SIZE: one per field expected");
  if (h.types.size() != h.fields.size()) fail_line(path, at("TYPE"), "TYPE: one per field expected");
  if (h.counts.empty()) h.counts.assign(h.fields.size(), 1);
  if (h.counts.size() != h.fields.size()) fail_line(path, at("COUNT"), "COUNT: one per field expected");
  for (size_t i = 0; i < h.fields.size(); ++i)
    if (h.types[i] == 'F' && h.sizes[i] != 4 && h.sizes[i] != 8) fail_line(path, at("TYPE"), "TYPE: F needs SIZE 4 or 8");
  constexpr uint64_t kMax = uint64_t{1} << 32;
  if (h.width >= kMax || h.height >= kMax || h.width * h.height >= kMax)
    fail_line(path, at("WIDTH"), "WIDTH/HEIGHT: too large");
  if (!have_points) h.points = h.width * h.height;
  if (h.points != h.width * h.height)
    fail_line(path, at("POINTS"), "POINTS: " + std::to_string(h.points) + " is not WIDTH x HEIGHT = " +
                           std::to_string(h.width * h.height));
  bool x = false, y = false, z = false;
  for (const auto& f : h.fields) x |= f == "x", y |= f == "y", z |= f == "z";
  if (!(x && y && z)) fail_line(path, at("FIELDS"), "FIELDS: no x y z");
  return h;
}

uint32_t le32(std::string_view b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  if constexpr (std::endian::native == std::endian::big) v = __builtin_bswap32(v);
  return v;
}

// PCL 1.13's header parser reads on past DATA while the next "line" starts
// with a header keyword, and then throws, allocates without bound or crashes
// (found by tests/fuzz/pcd_fuzz.cpp): such data is refused here, though a
// float's bytes spell a keyword only by chance. Ascii data too: without
// POINTS and WIDTH its lines are not read below, yet PCL reads them.
void refuse_header_keywords_in_data(const std::string& path, std::string_view text, const PcdHeader& h) {
  const size_t at = h.data_offset;
  static const char* keywords[] = {"VERSION", "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT",
                                   "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
  // PCL's loop skips blank lines and '#' comments before it looks for a
  // keyword at the start of a (whitespace-trimmed) line, so do the same.
  std::string_view data = text.substr(std::min(at, text.size()));
  size_t line_at = at;
  while (!data.empty()) {
    const size_t eol = data.find('\n');
    std::string_view line = data.substr(0, eol);
    const size_t first = line.find_first_not_of(" \t\r\v\f");
    line = first == std::string_view::npos ? std::string_view{} : line.substr(first);
    if (!line.empty() && line.front() != '#') {
      for (const char* k : keywords)
        if (line.starts_with(k))
          fail_byte(path, line_at,
                    std::string(h.data == "ascii" ? "ascii" : "binary") + " data has a line beginning with '" +
                        std::string(k) + "', which PCL's reader takes for a header line");
      break;
    }
    if (eol == std::string_view::npos) break;
    data.remove_prefix(eol + 1);
    line_at += eol + 1;
  }
}

void check_pcd_data(const std::string& path, std::string_view text, const PcdHeader& h) {
  uint64_t point_bytes = 0;
  size_t values = 0;
  for (size_t i = 0; i < h.fields.size(); ++i) {
    point_bytes += static_cast<uint64_t>(h.sizes[i]) * static_cast<uint64_t>(h.counts[i]);
    values += static_cast<size_t>(h.counts[i]);
  }
  const uint64_t need = point_bytes * h.points;
  const size_t at = h.data_offset;
  const size_t have = text.size() > at ? text.size() - at : 0;
  refuse_header_keywords_in_data(path, text, h);
  if (h.data == "binary") {
    if (need > have)
      fail_byte(path, text.size(), "binary data truncated: " + std::to_string(h.points) + " points need " +
                                       std::to_string(need) + " bytes, " + std::to_string(have) + " left");
  } else if (h.data == "binary_compressed") {
    if (have < 8) fail_byte(path, text.size(), "binary_compressed: no size words");
    const uint32_t compressed = le32(text, at), raw = le32(text, at + 4);
    if (raw != need)
      fail_byte(path, at + 4, "binary_compressed: " + std::to_string(raw) + " uncompressed bytes, " +
                                  std::to_string(need) + " expected");
    if (compressed > have - 8)
      fail_byte(path, text.size(), "binary_compressed data truncated: " + std::to_string(compressed) +
                                       " bytes announced, " + std::to_string(have - 8) + " left");
    if (need > 0 && compressed == 0) fail_byte(path, at, "binary_compressed: empty data");
    // LZF (PCL's codec) expands at most ~88x (3 bytes back-reference up to
    // 264): a larger claim is a corrupt size word, not a reason to allocate.
    if (raw > 100ull * compressed + 1024)
      fail_byte(path, at + 4, "binary_compressed: " + std::to_string(raw) + " uncompressed bytes cannot come from " +
                                  std::to_string(compressed));
  } else {
    // One point per line, each with every field's values.
    Lines lines{text.substr(std::min(at, text.size()))};
    std::string_view line;
    uint64_t seen = 0;
    while (seen < h.points && lines.next(line)) {
      const auto w = words(line);
      if (w.empty()) continue;
      if (w.size() != values)
        fail_line(path, h.data_line + lines.number,
                  "expected " + std::to_string(values) + " values, found " + std::to_string(w.size()));
      for (const auto& v : w) {
        double d;
        if (!parse(v, d) && v != "nan" && v != "NaN" && v != "-nan")
          fail_line(path, h.data_line + lines.number, "not a number: '" + std::string(v) + "'");
      }
      ++seen;
    }
    if (seen < h.points)
      fail_line(path, h.data_line + lines.number,
                "ascii data: " + std::to_string(seen) + " points, " + std::to_string(h.points) + " announced");
  }
}

PcdHeader check_pcd(const std::string& path, std::string_view text) {
  PcdHeader h = parse_pcd_header(path, text);
  check_pcd_data(path, text, h);
  return h;
}

std::string canonical_pcd_header(const PcdHeader& h) {
  std::ostringstream o;
  o.precision(17);
  o << "VERSION 0.7\nFIELDS";
  for (const auto& f : h.fields) o << ' ' << f;
  o << "\nSIZE";
  for (int v : h.sizes) o << ' ' << v;
  o << "\nTYPE";
  for (char t : h.types) o << ' ' << t;
  o << "\nCOUNT";
  for (int v : h.counts) o << ' ' << v;
  o << "\nWIDTH " << h.width << "\nHEIGHT " << h.height << "\nVIEWPOINT";
  for (double v : h.viewpoint) o << ' ' << v;
  o << "\nPOINTS " << h.points << "\nDATA " << h.data << '\n';
  return std::move(o).str();
}

// ---------------------------------------------------------------- PLY ----

enum class PlyType { I8, U8, I16, U16, I32, U32, F32, F64 };

bool ply_type(std::string_view s, PlyType& t) {
  static const std::pair<std::string_view, PlyType> names[] = {
      {"char", PlyType::I8},    {"int8", PlyType::I8},     {"uchar", PlyType::U8},    {"uint8", PlyType::U8},
      {"short", PlyType::I16},  {"int16", PlyType::I16},   {"ushort", PlyType::U16},  {"uint16", PlyType::U16},
      {"int", PlyType::I32},    {"int32", PlyType::I32},   {"uint", PlyType::U32},    {"uint32", PlyType::U32},
      {"float", PlyType::F32},  {"float32", PlyType::F32}, {"double", PlyType::F64},  {"float64", PlyType::F64}};
  for (const auto& [name, type] : names)
    if (s == name) return t = type, true;
  return false;
}

size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::I8: case PlyType::U8: return 1;
    case PlyType::I16: case PlyType::U16: return 2;
    case PlyType::F64: return 8;
    default: return 4;
  }
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::F32;
  bool list = false;
  PlyType count_type = PlyType::U8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

// Binary values, bounds-checked, in the file's byte order.
struct Bytes {
  const std::string& path;
  std::string_view data;
  size_t pos;
  bool big_endian;

  double read(PlyType t) {
    const size_t n = ply_size(t);
    if (data.size() - pos < n) fail_byte(path, pos, "binary data truncated");
    uint8_t b[8];
    std::memcpy(b, data.data() + pos, n);
    if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
    pos += n;
    switch (t) {
      case PlyType::I8: return static_cast<int8_t>(b[0]);
      case PlyType::U8: return b[0];
      case PlyType::I16: { int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::U16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::I32: { int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::U32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::F32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::F64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0.0;
  }
};

enum class PlyFormat { None, Ascii, Little, Big };

struct PlyHeader {
  PlyFormat format = PlyFormat::None;
  std::vector<PlyElement> elements;
};

// A property line's words: "<type> <name>" or "list <type> <type> <name>".
PlyProperty ply_property(const std::string& path, size_t n, const std::vector<std::string_view>& w) {
  PlyProperty p;
  if (w.size() == 5 && w[1] == "list") {
    p.list = true;
    if (!ply_type(w[2], p.count_type) || !ply_type(w[3], p.type)) fail_line(path, n, "property: unknown list type");
    if (p.count_type == PlyType::F32 || p.count_type == PlyType::F64)
      fail_line(path, n, "property: a list count must be an integer type");
    p.name = std::string(w[4]);
  } else if (w.size() == 3) {
    if (!ply_type(w[1], p.type)) fail_line(path, n, "property: unknown type '" + std::string(w[1]) + "'");
    p.name = std::string(w[2]);
  } else {
    fail_line(path, n, "property: expected '<type> <name>' or 'list <type> <type> <name>'");
  }
  return p;
}

// The header up to end_header; `lines` is left on the first data byte.
PlyHeader parse_ply_header(const std::string& path, Lines& lines) {
  std::string_view line;
  if (!lines.next(line) || line != "ply") fail_line(path, 1, "not a PLY file (first line is not 'ply')");
  PlyHeader h;
  bool ended = false;
  while (lines.next(line)) {
    const auto w = words(line);
    const size_t n = lines.number;
    if (w.empty()) continue;
    if (w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "format") {
      if (w.size() != 3 || w[2] != "1.0") fail_line(path, n, "format: expected '<kind> 1.0'");
      if (w[1] == "ascii") h.format = PlyFormat::Ascii;
      else if (w[1] == "binary_little_endian") h.format = PlyFormat::Little;
      else if (w[1] == "binary_big_endian") h.format = PlyFormat::Big;
      else fail_line(path, n, "format: unknown '" + std::string(w[1]) + "'");
    } else if (w[0] == "element") {
      if (w.size() != 3) fail_line(path, n, "element: expected a name and a count");
      h.elements.push_back({std::string(w[1]), number<uint64_t>(w[2], path, n, "element"), {}});
    } else if (w[0] == "property") {
      if (h.elements.empty()) fail_line(path, n, "property: before any element");
      h.elements.back().properties.push_back(ply_property(path, n, w));
    } else if (w[0] == "end_header") {
      ended = true;
      break;
    } else {
      fail_line(path, n, "unknown header keyword '" + std::string(w[0]) + "'");
    }
  }
  if (!ended) fail_line(path, lines.number, "end_header: missing");
  if (h.format == PlyFormat::None) fail_line(path, lines.number, "format: missing");
  return h;
}

// The vertex element, where its x y z (and nx ny nz) are among its
// properties, and the cloud its instances make.
struct PlyVertices {
  const PlyElement* vertex = nullptr;
  int ix[6] = {-1, -1, -1, -1, -1, -1};
  bool normals = false;
  Cloud cloud;

  // One vertex from its properties' values (a list's value is 0).
  void take(const std::vector<double>& values) {
    const Eigen::Vector3f p(static_cast<float>(values[static_cast<size_t>(ix[0])]),
                            static_cast<float>(values[static_cast<size_t>(ix[1])]),
                            static_cast<float>(values[static_cast<size_t>(ix[2])]));
    if (!finite(p)) return;
    cloud.points.push_back(p);
    if (normals) {
      Eigen::Vector3f m(static_cast<float>(values[static_cast<size_t>(ix[3])]),
                        static_cast<float>(values[static_cast<size_t>(ix[4])]),
                        static_cast<float>(values[static_cast<size_t>(ix[5])]));
      const float len = m.norm();
      cloud.normals.push_back(std::isfinite(len) && len > 0.0f ? Eigen::Vector3f(m / len) : Eigen::Vector3f::Zero());
    }
  }
};

PlyVertices ply_vertices(const std::string& path, const Lines& lines, const std::vector<PlyElement>& elements) {
  PlyVertices v;
  for (const auto& e : elements)
    if (e.name == "vertex") v.vertex = &e;
  if (v.vertex == nullptr) fail_line(path, lines.number, "element vertex: missing");
  static const char* wanted[6] = {"x", "y", "z", "nx", "ny", "nz"};
  const auto& properties = v.vertex->properties;
  for (size_t i = 0; i < properties.size(); ++i)
    for (int k = 0; k < 6; ++k)
      if (properties[i].name == wanted[k] && !properties[i].list) v.ix[k] = static_cast<int>(i);
  if (v.ix[0] < 0 || v.ix[1] < 0 || v.ix[2] < 0) fail_line(path, lines.number, "element vertex: no x y z properties");
  v.normals = v.ix[3] >= 0 && v.ix[4] >= 0 && v.ix[5] >= 0;

  // Every element needs at least a byte (binary) or a character per
  // instance: a count beyond the file's size is refused before reserving.
  const size_t left = lines.text.size() - std::min(lines.pos, lines.text.size());
  for (const auto& e : elements)
    if (e.count > left) fail_line(path, lines.number, "element " + e.name + ": count " + std::to_string(e.count) +
                                                          " exceeds the data's " + std::to_string(left) + " bytes");
  v.cloud.points.reserve(v.vertex->count);
  if (v.normals) v.cloud.normals.reserve(v.vertex->count);
  return v;
}

// Every element's instances as text lines, from where `lines` stands.
void read_ply_ascii(const std::string& path, Lines& lines, const std::vector<PlyElement>& elements, PlyVertices& out) {
  std::vector<double> values;
  for (const auto& e : elements) {
    const bool is_vertex = &e == out.vertex;
    for (uint64_t k = 0; k < e.count; ++k) {
      std::string_view l;
      std::vector<std::string_view> w;
      do {
        if (!lines.next(l)) fail_line(path, lines.number, "element " + e.name + ": " + std::to_string(k) + " of " +
                                                              std::to_string(e.count) + " found, file ends");
        w = words(l);
      } while (w.empty());
      const size_t n = lines.number;
      size_t t = 0;
      values.clear();
      for (const auto& p : e.properties) {
        if (t >= w.size()) fail_line(path, n, "element " + e.name + ": too few values for '" + p.name + "'");
        if (p.list) {
          const uint64_t c = number<uint64_t>(w[t++], path, n, p.name);
          if (c > w.size() - t) fail_line(path, n, "element " + e.name + ": list '" + p.name + "' too short");
          for (uint64_t j = 0; j < c; ++j) (void)number<double>(w[t++], path, n, p.name);
          values.push_back(0.0);
        } else {
          values.push_back(number<double>(w[t++], path, n, p.name));
        }
      }
      if (t != w.size()) fail_line(path, n, "element " + e.name + ": " + std::to_string(w.size() - t) + " values too many");
      if (is_vertex) out.take(values);
    }
  }
}

// Every element's instances as bytes in the file's order, from `b.pos`.
void read_ply_binary(Bytes& b, const std::vector<PlyElement>& elements, PlyVertices& out) {
  std::vector<double> values;
  for (const auto& e : elements) {
    const bool is_vertex = &e == out.vertex;
    for (uint64_t k = 0; k < e.count; ++k) {
      values.clear();
      for (const auto& p : e.properties) {
        if (p.list) {
          const size_t at = b.pos;
          const double c = b.read(p.count_type);
          if (c < 0) fail_byte(b.path, at, "list '" + p.name + "': negative count");
          const size_t bytes = static_cast<size_t>(c) * ply_size(p.type);
          if (bytes > b.data.size() - b.pos) fail_byte(b.path, b.pos, "binary data truncated in list '" + p.name + "'");
          b.pos += bytes;
          values.push_back(0.0);
        } else {
          values.push_back(b.read(p.type));
        }
      }
      if (is_vertex) out.take(values);
    }
  }
}

// PLY (Turk's format as in "The PLY Polygon File Format"): the vertex
// element's x y z and nx ny nz; every other property and element is read
// past.
Cloud parse_ply(const std::string& path, std::string_view text) {
  Lines lines{text};
  const PlyHeader h = parse_ply_header(path, lines);
  PlyVertices v = ply_vertices(path, lines, h.elements);
  if (h.format == PlyFormat::Ascii) {
    read_ply_ascii(path, lines, h.elements, v);
  } else {
    Bytes b{path, text, lines.pos, h.format == PlyFormat::Big};
    if (b.pos > text.size()) b.pos = text.size();
    read_ply_binary(b, h.elements, v);
  }
  return std::move(v.cloud);
}

// ---------------------------------------------------------------- XYZ ----

Cloud parse_xyz(const std::string& path, std::string_view text) {
  Cloud cloud;
  Lines lines{text};
  std::string_view line;
  size_t columns = 0;
  while (lines.next(line)) {
    const auto w = words(line);
    if (w.empty() || w[0].front() == '#') continue;
    const size_t n = lines.number;
    if (columns == 0) {
      if (w.size() != 3 && w.size() != 6) fail_line(path, n, "expected 'x y z' or 'x y z nx ny nz'");
      columns = w.size();
    }
    if (w.size() != columns)
      fail_line(path, n, "expected " + std::to_string(columns) + " values as on the first line, found " +
                             std::to_string(w.size()));
    const Eigen::Vector3f p(number<float>(w[0], path, n, "x"), number<float>(w[1], path, n, "y"),
                            number<float>(w[2], path, n, "z"));
    if (!finite(p)) continue;
    cloud.points.push_back(p);
    if (columns == 6)
      cloud.normals.emplace_back(number<float>(w[3], path, n, "nx"), number<float>(w[4], path, n, "ny"),
                                 number<float>(w[5], path, n, "nz"));
  }
  return cloud;
}

// --------------------------------------------------------------- 3DTK ----

// 3DTK's uos format (src/scanio/scan_io_uos.cc): an optional "W x H" first
// line, then "x y z" in cm per line. Like 3DTK, only a first line of that
// form is taken as a header; any other first line is a point.
Cloud parse_3d(const std::string& path, std::string_view text) {
  Cloud cloud;
  Lines lines{text};
  std::string_view line;
  while (lines.next(line)) {
    const auto w = words(line);
    const size_t n = lines.number;
    if (w.empty()) continue;
    if (n == 1 && w.size() == 3 && w[1] == "x") {
      uint64_t a, b;
      if (parse(w[0], a) && parse(w[2], b)) continue;
    }
    if (w.size() < 3) fail_line(path, n, "expected 'x y z' (cm)");
    const Eigen::Vector3f p_cm(number<float>(w[0], path, n, "x"), number<float>(w[1], path, n, "y"),
                               number<float>(w[2], path, n, "z"));
    if (!finite(p_cm)) continue;
    cloud.points.push_back(from_3dtk_point(p_cm));
  }
  return cloud;
}

// 3DTK's change of basis: ours (x forward, y left, z up) = C · theirs
// (x right, y up, z forward). det C = -1: it turns their left-handed frame
// into our right-handed one.
Eigen::Matrix3d basis_3dtk() {
  Eigen::Matrix3d C;
  C << 0, 0, 1,  //
      -1, 0, 0,  //
      0, 1, 0;
  return C;
}

std::vector<double> read_numbers(const std::string& path, std::string_view text, size_t count) {
  std::vector<double> v;
  Lines lines{text};
  std::string_view line;
  while (lines.next(line))
    for (const auto& w : words(line)) {
      if (v.size() == count) fail_line(path, lines.number, "more than " + std::to_string(count) + " numbers");
      v.push_back(number<double>(w, path, lines.number, "pose"));
    }
  if (v.size() != count)
    fail_line(path, lines.number, "expected " + std::to_string(count) + " numbers, found " + std::to_string(v.size()));
  return v;
}

// The simulator's `.pose` (sim/README.md, "Scan files"): key/value lines.
Eigen::Isometry3d parse_sim_pose(const std::string& path, std::string_view text) {
  Lines lines{text};
  std::string_view line;
  double t[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
  bool have_t = false, have_q = false;
  while (lines.next(line)) {
    const auto w = words(line);
    if (w.empty() || w[0].front() == '#') continue;
    const size_t n = lines.number;
    const std::string key(w[0]);
    const auto expect = [&](size_t k) {
      if (w.size() != k + 1) fail_line(path, n, key + ": expected " + std::to_string(k) + " numbers");
    };
    if (key == "time_s") {
      expect(1);
      (void)number<double>(w[1], path, n, key);
    } else if (key == "position_m") {
      expect(3);
      for (size_t i = 0; i < 3; ++i) t[i] = number<double>(w[1 + i], path, n, key);
      have_t = true;
    } else if (key == "orientation_wxyz") {
      expect(4);
      for (size_t i = 0; i < 4; ++i) q[i] = number<double>(w[1 + i], path, n, key);
      have_q = true;
    } else if (key == "matrix_row_major") {
      expect(16);
    } else {
      fail_line(path, n, "unknown key '" + key + "'");
    }
  }
  if (!have_t) fail_line(path, lines.number, "position_m: missing");
  if (!have_q) fail_line(path, lines.number, "orientation_wxyz: missing");
  const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
  if (!(quat.norm() > 1e-9) || !std::isfinite(quat.norm())) fail_line(path, lines.number, "orientation_wxyz: not a rotation");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = quat.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
  return T;
}


Eigen::Isometry3d parse_3dtk_pose(const std::string& path, std::string_view text) {
  const auto v = read_numbers(path, text, 6);
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  return from_3dtk_pose(euler_3dtk({v[0], v[1], v[2]}, Eigen::Vector3d(v[3], v[4], v[5]) * kDeg));
}

Range3dtk parse_3dtk_config(const std::string& path, std::string_view text) {
  // 3DTK's programs read their options from a config.ini in the scan folder
  // ("key=value", '#' comments); of those only the range limits say
  // something about the data: `max` (cm) is where its scanner writes a
  // missing return.
  Range3dtk range;
  Lines lines{text};
  std::string_view line;
  while (lines.next(line)) {
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    const size_t eq = line.find('=');
    const auto key_words = words(line.substr(0, eq));
    if (key_words.empty()) continue;
    const size_t n = lines.number;
    if (eq == std::string_view::npos) fail_line(path, n, std::string(key_words[0]) + ": expected key=value");
    const auto value = words(line.substr(eq + 1));
    const std::string key(key_words[0]);
    if (key != "min" && key != "max") continue;
    if (value.size() != 1) fail_line(path, n, key + ": expected one number");
    const double v = number<double>(value[0], path, n, key);
    if (!(v >= 0.0) || !std::isfinite(v)) fail_line(path, n, key + ": must be a distance >= 0 (cm)");
    (key == "min" ? range.min_m : range.max_m) = v / 100.0;
  }
  if (range.max_m > 0.0 && range.min_m >= range.max_m) fail_line(path, lines.number, "min must be below max");
  return range;
}

std::vector<Eigen::Isometry3d> parse_3dtk_frames(const std::string& path, std::string_view text) {
  std::vector<Eigen::Isometry3d> frames;
  Lines lines{text};
  std::string_view line;
  while (lines.next(line)) {
    const auto w = words(line);
    if (w.empty()) continue;
    const size_t n = lines.number;
    if (w.size() != 17) fail_line(path, n, "expected 16 matrix entries and a colour code, found " +
                                               std::to_string(w.size()) + " values");
    Eigen::Matrix4d M;
    for (int i = 0; i < 16; ++i) M(i % 4, i / 4) = number<double>(w[static_cast<size_t>(i)], path, n, "matrix");
    (void)number<double>(w[16], path, n, "colour");
    if (!M.allFinite() || (M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-6)
      fail_line(path, n, "not a rigid transform (bottom row must be 0 0 0 1)");
    const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
    if ((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-3)
      fail_line(path, n, "not a rigid transform (rotation not orthonormal)");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
    T.translation() = M.topRightCorner<3, 1>();
    frames.push_back(from_3dtk_pose(T));
  }
  if (frames.empty()) fail_line(path, lines.number, "no frames");
  return frames;
}

}  // namespace rise::semantic::formats

namespace rise::semantic {

Eigen::Vector3f from_3dtk_point(const Eigen::Vector3f& p_cm) {
  return Eigen::Vector3f(p_cm.z(), -p_cm.x(), p_cm.y()) * 0.01f;
}

Eigen::Isometry3d from_3dtk_pose(const Eigen::Isometry3d& T_3dtk_cm) {
  const Eigen::Matrix3d C = formats::basis_3dtk();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = C * T_3dtk_cm.linear() * C.transpose();
  T.translation() = C * T_3dtk_cm.translation() * 0.01;
  return T;
}

Eigen::Isometry3d euler_3dtk(const Eigen::Vector3d& position_cm, const Eigen::Vector3d& angles_rad) {
  // slam6d's EulerToMatrix4 (include/slam6d/globals.icc): R = Rx · Ry · Rz.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(angles_rad.x(), Eigen::Vector3d::UnitX()) *
                Eigen::AngleAxisd(angles_rad.y(), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(angles_rad.z(), Eigen::Vector3d::UnitZ()))
                   .toRotationMatrix();
  T.translation() = position_cm;
  return T;
}

}  // namespace rise::semantic
