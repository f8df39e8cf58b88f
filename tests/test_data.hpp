#pragma once

// The shared public test data (../shared/data, MANIFEST.md there), reached
// only through RISE_TEST_DATA, which CMake sets for every test.

#include <cstdlib>
#include <filesystem>
#include <string>

namespace rise::test {

/// The path of RISE_TEST_DATA/relative, or "" when the variable is unset or
/// the file is absent (the caller then WARNs "skipped: ..." and returns).
inline std::string data_file(const std::string& relative) {
  const char* root = std::getenv("RISE_TEST_DATA");
  if (root == nullptr) return {};
  const std::filesystem::path p = std::filesystem::path(root) / relative;
  return std::filesystem::exists(p) ? p.string() : std::string{};
}

}  // namespace rise::test
