// libFuzzer target: PCD files. Our own header and size check
// (formats::check_pcd, sanitized here) on every input; inputs it accepts go
// on through the whole reader, PCL's pcl::PCDReader included (PCL is the
// system's uninstrumented library: ASan sees its heap, not its every load).
// An error must be a std::runtime_error whose text starts with "fuzz.pcd";
// every point read must be finite.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "semantic/cloud_formats.hpp"
#include "semantic/cloud_io.hpp"

namespace sem = rise::semantic;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    (void)sem::formats::check_pcd("fuzz.pcd", bytes);
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.pcd"));
    return 0;
  }
  try {
    const sem::Cloud c = sem::parse_cloud("fuzz.pcd", bytes);
    check(c.normals.empty() || c.normals.size() == c.points.size());
    for (const auto& p : c.points) check(p.allFinite());
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.pcd"));
  }
  return 0;
}
