// libFuzzer target: the PLY reader (ascii, binary little and big endian) and
// the XYZ reader on arbitrary bytes. An error must be a std::runtime_error
// whose text starts with the file name; every point read must be finite and
// normals, if any, one per point.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "semantic/cloud_formats.hpp"

namespace fmt = rise::semantic::formats;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

void check_cloud(const rise::semantic::Cloud& c) {
  check(c.normals.empty() || c.normals.size() == c.points.size());
  for (const auto& p : c.points) check(p.allFinite());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    check_cloud(fmt::parse_ply("fuzz.ply", bytes));
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.ply"));
  }
  try {
    check_cloud(fmt::parse_xyz("fuzz.xyz", bytes));
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.xyz:"));
  }
  return 0;
}
