// Legacy VTK files ("VTK File Formats", VTK User's Guide, and VTK 9's
// vtkDataReader): a version line, a title line, ASCII or BINARY, then
// keyword lines, each followed by its data — whitespace-separated numbers
// in ASCII, big-endian values right after the keyword line's newline in
// BINARY. E.g. a point at (1, 2, 3) as BINARY float:
//   "POINTS 1 float\n" 3f 80 00 00  40 00 00 00  40 40 00 00 "\n"
// VTK 9 writes version 5.1, whose cell sections are two arrays
// ("POLYGONS 2 3\nOFFSETS vtktypeint64\n…\nCONNECTIVITY vtktypeint64\n…");
// before 5 a cell section is one int array ("POLYGONS 1 4\n3 0 1 2").
// Kept apart from VTK's headers: only the tests include those.

#include <algorithm>
#include <bit>
#include <cmath>

#include "semantic/cloud_formats.hpp"

namespace rise::semantic::formats {
namespace {

// A value type of the format; size 0 for "bit" (packed, 8 per byte).
struct VtkType {
  std::string_view name;
  size_t size;
  bool floating;
  bool is_signed;
};

constexpr VtkType kVtkTypes[] = {
    {"bit", 0, false, false},          {"char", 1, false, true},          {"signed_char", 1, false, true},
    {"unsigned_char", 1, false, false}, {"short", 2, false, true},        {"unsigned_short", 2, false, false},
    {"int", 4, false, true},           {"unsigned_int", 4, false, false}, {"long", 8, false, true},
    {"unsigned_long", 8, false, false}, {"vtkidtype", 8, false, true},    {"vtktypeint64", 8, false, true},
    {"vtktypeuint64", 8, false, false}, {"float", 4, true, true},         {"double", 8, true, true}};

std::string lower(std::string_view s) {
  std::string l(s);
  std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return l;
}

// One keyword line: its words (the first lowercased, as VTK compares them)
// and its number.
struct KeyLine {
  std::string key, name;  // lowercased, and as written
  std::vector<std::string_view> args;
  size_t line = 0;
};

class VtkReader {
 public:
  VtkReader(const std::string& path, std::string_view text) : path_(path), text_(text) {}

  Cloud read() {
    read_preamble();
    while (true) {
      const KeyLine k = next_key();
      if (k.key.empty()) break;
      read_section(k);
    }
    if (!saw_points_) fail_line(path_, last_line(), "POINTS: missing");
    return cloud();
  }

 private:
  // The version, title and format lines, and DATASET with a point list.
  void read_preamble() {
    Lines lines{text_};
    std::string_view line;
    static constexpr std::string_view kMagic = "# vtk DataFile Version";
    if (!lines.next(line) || !line.starts_with(kMagic))
      fail_line(path_, 1, "not a legacy VTK file (first line is not '" + std::string(kMagic) + " x.y')");
    const auto version = words(line.substr(kMagic.size()));
    if (version.size() != 1) fail_line(path_, 1, "version: expected 'x.y'");
    major_ = number<int>(version[0].substr(0, version[0].find('.')), path_, 1, "version");
    if (!lines.next(line)) fail_line(path_, 2, "title line missing");
    if (!lines.next(line)) fail_line(path_, 3, "ASCII or BINARY missing");
    const auto format = words(line);
    if (format.size() != 1 || (lower(format[0]) != "ascii" && lower(format[0]) != "binary"))
      fail_line(path_, 3, "expected ASCII or BINARY");
    binary_ = lower(format[0]) == "binary";
    pos_ = std::min(lines.pos, text_.size());

    const KeyLine dataset = next_key();
    if (dataset.key != "dataset" || dataset.args.size() != 1)
      fail_line(path_, dataset.key.empty() ? last_line() : dataset.line, "expected 'DATASET <type>'");
    const std::string type = lower(dataset.args[0]);
    if (type != "polydata" && type != "unstructured_grid" && type != "structured_grid")
      fail_line(path_, dataset.line, "DATASET: '" + std::string(dataset.args[0]) +
                                         "' has no point list (expected POLYDATA, UNSTRUCTURED_GRID or STRUCTURED_GRID)");
  }

  // One keyword line's section: the points and the points' normals kept,
  // everything else read past.
  void read_section(const KeyLine& k) {
    const auto count = [&](size_t i) { return arg<uint64_t>(k, i); };
    if (k.key == "points") {
      expect_args(k, 2);
      if (saw_points_) fail_line(path_, k.line, "POINTS: given twice");
      values(k, count(0), 3, k.args[1], &xyz_);
    } else if (k.key == "dimensions") {
      expect_args(k, 3);
      for (size_t i = 0; i < 3; ++i) (void)count(i);
    } else if (k.key == "vertices" || k.key == "lines" || k.key == "polygons" || k.key == "triangle_strips" ||
               k.key == "cells") {
      expect_args(k, 2);
      if (major_ >= 5) {
        array_after(k, "OFFSETS", count(0));
        array_after(k, "CONNECTIVITY", count(1));
      } else {
        values(k, count(1), 1, "int", nullptr);
      }
    } else if (k.key == "cell_types") {
      expect_args(k, 1);
      values(k, count(0), 1, "int", nullptr);
    } else if (k.key == "point_data" || k.key == "cell_data") {
      expect_args(k, 1);
      tuples_ = count(0);
      point_data_ = k.key == "point_data";
    } else if (k.key == "scalars") {
      if (k.args.size() != 2 && k.args.size() != 3) fail_line(path_, k.line, "SCALARS: expected a name, a type and optionally a count");
      const uint64_t components = k.args.size() == 3 ? count(2) : 1;
      // The LOOKUP_TABLE line that belongs to the scalars.
      const size_t at = pos_;
      const KeyLine table = next_key();
      if (table.key != "lookup_table") pos_ = at;
      values(k, tuples_, components, k.args[1], nullptr);
    } else if (k.key == "lookup_table") {
      expect_args(k, 2);
      values(k, count(1), 4, binary_ ? "unsigned_char" : "float", nullptr);
    } else if (k.key == "color_scalars") {
      expect_args(k, 2);
      values(k, tuples_, count(1), binary_ ? "unsigned_char" : "float", nullptr);
    } else if (k.key == "normals") {
      expect_args(k, 2);
      values(k, tuples_, 3, k.args[1], point_data_ ? &normals_ : nullptr);
    } else if (k.key == "vectors" || k.key == "tensors" || k.key == "tensors6") {
      expect_args(k, 2);
      values(k, tuples_, k.key == "vectors" ? 3 : k.key == "tensors" ? 9 : 6, k.args[1], nullptr);
    } else if (k.key == "texture_coordinates") {
      expect_args(k, 3);
      values(k, tuples_, count(1), k.args[2], nullptr);
    } else if (k.key == "global_ids" || k.key == "pedigree_ids" || k.key == "edge_flags") {
      expect_args(k, 2);
      values(k, tuples_, 1, k.args[1], nullptr);
    } else if (k.key == "field") {
      expect_args(k, 2);
      skip_field_arrays(count(1));
    } else if (k.key == "metadata") {
      skip_metadata();
    } else {
      fail_line(path_, k.line, "unknown keyword '" + k.name + "'");
    }
  }

  // FIELD's arrays, each "name components tuples type" and its values.
  void skip_field_arrays(uint64_t arrays) {
    uint64_t read = 0;
    while (read < arrays) {
      const KeyLine a = next_key();
      if (a.key.empty())
        fail_line(path_, last_line(), "FIELD: file ends after " + std::to_string(read) + " of " + std::to_string(arrays) + " arrays");
      if (a.key == "metadata") {
        skip_metadata();
        continue;
      }
      ++read;
      if (a.key == "null_array") continue;
      expect_args(a, 3);
      values(a, arg<uint64_t>(a, 1), arg<uint64_t>(a, 0), a.args[2], nullptr);
    }
  }

  // The finite points, with their normals (unit length, zero where there is
  // none) when POINT_DATA gave one per point.
  Cloud cloud() const {
    const size_t n = xyz_.size() / 3;
    if (!normals_.empty() && normals_.size() != xyz_.size())
      fail_line(path_, normals_line_, "NORMALS: " + std::to_string(normals_.size() / 3) + " normals for " +
                                          std::to_string(n) + " points");
    Cloud cloud;
    cloud.points.reserve(n);
    if (!normals_.empty()) cloud.normals.reserve(n);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3f p(static_cast<float>(xyz_[3 * i]), static_cast<float>(xyz_[3 * i + 1]),
                              static_cast<float>(xyz_[3 * i + 2]));
      if (!p.allFinite()) continue;
      cloud.points.push_back(p);
      if (normals_.empty()) continue;
      const Eigen::Vector3f m(static_cast<float>(normals_[3 * i]), static_cast<float>(normals_[3 * i + 1]),
                              static_cast<float>(normals_[3 * i + 2]));
      const float len = m.norm();
      cloud.normals.push_back(std::isfinite(len) && len > 0.0f ? Eigen::Vector3f(m / len) : Eigen::Vector3f::Zero());
    }
    return cloud;
  }

  // The 1-based line of byte `at`, counting on from the last question (the
  // reader asks in file order, so the file is counted through once).
  size_t line_at(size_t at) const {
    at = std::min(at, text_.size());
    if (at < counted_to_) counted_to_ = 0, counted_lines_ = 0;
    const auto from = text_.begin() + static_cast<std::ptrdiff_t>(counted_to_);
    counted_lines_ += static_cast<size_t>(std::count(from, text_.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
    counted_to_ = at;
    return 1 + counted_lines_;
  }

  size_t last_line() const { return line_at(text_.size()) - (text_.ends_with('\n') ? 1 : 0); }

  void skip_space() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }

  // The next non-blank line as a keyword line; pos_ after its newline (where
  // BINARY data starts). An empty key at the end of the file.
  KeyLine next_key() {
    skip_space();
    KeyLine k;
    if (pos_ >= text_.size()) return k;
    k.line = line_at(pos_);
    const size_t end = std::min(text_.find('\n', pos_), text_.size());
    auto w = words(text_.substr(pos_, end - pos_));
    pos_ = std::min(end + 1, text_.size());
    k.name = std::string(w.front());
    k.key = lower(k.name);
    k.args.assign(w.begin() + 1, w.end());
    return k;
  }

  // METADATA: lines up to the first blank one (vtkDataReader::ReadInformation).
  void skip_metadata() {
    while (pos_ < text_.size()) {
      const size_t end = std::min(text_.find('\n', pos_), text_.size());
      const bool blank = words(text_.substr(pos_, end - pos_)).empty();
      pos_ = std::min(end + 1, text_.size());
      if (blank) return;
    }
  }

  void expect_args(const KeyLine& k, size_t n) const {
    if (k.args.size() != n)
      fail_line(path_, k.line, k.name + ": expected " + std::to_string(n) + " values after the keyword, found " +
                                   std::to_string(k.args.size()));
  }

  template <typename T>
  T arg(const KeyLine& k, size_t i) const {
    return number<T>(k.args[i], path_, k.line, k.name);
  }

  // A version 5 cell array: its "OFFSETS type" / "CONNECTIVITY type" line, then the values.
  void array_after(const KeyLine& cells, const char* name, uint64_t n) {
    const KeyLine k = next_key();
    if (k.key != lower(name) || k.args.size() != 1)
      fail_line(path_, k.key.empty() ? last_line() : k.line, cells.name + ": expected '" + name + " <type>' next");
    values(k, n, 1, k.args[0], nullptr);
  }

  // `tuples` × `components` values of `type_name`, kept in `out` if given.
  void values(const KeyLine& k, uint64_t tuples, uint64_t components, std::string_view type_name, std::vector<double>* out) {
    const std::string t = lower(type_name);
    const VtkType* type = nullptr;
    for (const auto& v : kVtkTypes)
      if (v.name == t) type = &v;
    if (type == nullptr) fail_line(path_, k.line, k.name + ": unsupported value type '" + std::string(type_name) + "'");
    if (k.key == "points") saw_points_ = true;
    if (k.key == "normals" && out != nullptr) normals_line_ = k.line;
    // Each value takes at least a byte (binary) or a digit and a space
    // (ascii): a count beyond that is refused before anything is reserved.
    const size_t left = text_.size() - pos_;
    if (components > left || (components > 0 && tuples > left / components))
      fail_line(path_, k.line, k.name + ": " + std::to_string(tuples) + " x " + std::to_string(components) +
                                   " values cannot fit in the " + std::to_string(left) + " bytes left");
    const uint64_t n = tuples * components;
    if (out != nullptr) out->reserve(out->size() + n);
    if (!binary_) {
      for (uint64_t i = 0; i < n; ++i) {
        skip_space();
        const size_t b = pos_;
        while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
        if (pos_ == b)
          fail_line(path_, k.line, k.name + ": file ends after " + std::to_string(i) + " of " + std::to_string(n) + " values");
        const double v = number<double>(text_.substr(b, pos_ - b), path_, line_at(b), k.name);
        if (out != nullptr) out->push_back(v);
      }
      return;
    }
    const uint64_t bytes = type->size == 0 ? (n + 7) / 8 : n * type->size;
    if (bytes > left)
      fail_byte(path_, pos_, k.name + ": binary data truncated: " + std::to_string(n) + " values need " +
                                 std::to_string(bytes) + " bytes, " + std::to_string(left) + " left");
    if (out != nullptr)
      for (uint64_t i = 0; i < n; ++i) out->push_back(big_endian(*type, pos_ + i * type->size));
    pos_ += bytes;
  }

  double big_endian(const VtkType& type, size_t at) const {
    uint64_t u = 0;
    for (size_t b = 0; b < type.size; ++b) u = u << 8 | static_cast<unsigned char>(text_[at + b]);
    if (type.floating) return type.size == 4 ? std::bit_cast<float>(static_cast<uint32_t>(u)) : std::bit_cast<double>(u);
    if (type.is_signed && type.size < 8 && (u >> (8 * type.size - 1)) != 0) u |= ~uint64_t{0} << (8 * type.size);
    return type.is_signed ? static_cast<double>(static_cast<int64_t>(u)) : static_cast<double>(u);
  }

  const std::string& path_;
  std::string_view text_;
  size_t pos_ = 0;
  bool binary_ = false;
  int major_ = 0;
  bool saw_points_ = false;
  size_t normals_line_ = 0;
  std::vector<double> xyz_, normals_;
  bool point_data_ = false;  // in POINT_DATA (NORMALS there are the points')
  uint64_t tuples_ = 0;      // the current attribute section's count
  mutable size_t counted_to_ = 0, counted_lines_ = 0;
};

}  // namespace

Cloud parse_vtk(const std::string& path, std::string_view text) { return VtkReader(path, text).read(); }

}  // namespace rise::semantic::formats
