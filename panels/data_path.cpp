#include "panels/data_path.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace rise::panels {

std::string find_data_file(const std::string& relative) {
  namespace fs = std::filesystem;
  if (fs::exists(relative)) return relative;
  if (const char* root = std::getenv("RISE_ROOT")) {
    const fs::path p = fs::path(root) / relative;
    if (fs::exists(p)) return p.string();
  }
  // Installed (packaging/CMakeLists.txt): <prefix>/bin/../share/rise. Run from
  // build/bin, build/share/rise does not exist and the source tree answers.
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path p = (exe.parent_path() / RISE_DATA_FROM_BIN / relative).lexically_normal();
    if (fs::exists(p)) return p.string();
  }
  const fs::path p = fs::path(RISE_SOURCE_DIR) / relative;
  if (fs::exists(p)) return p.string();
  return relative;
}

}  // namespace rise::panels
