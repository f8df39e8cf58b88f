#include "panels/data_path.hpp"

#include <cstdlib>
#include <filesystem>

namespace rise::panels {

std::string find_data_file(const std::string& relative) {
  namespace fs = std::filesystem;
  if (fs::exists(relative)) return relative;
  if (const char* root = std::getenv("RISE_ROOT")) {
    const fs::path p = fs::path(root) / relative;
    if (fs::exists(p)) return p.string();
  }
  const fs::path p = fs::path(RISE_SOURCE_DIR) / relative;
  if (fs::exists(p)) return p.string();
  return relative;
}

}  // namespace rise::panels
