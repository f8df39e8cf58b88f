#include "instructor/design_files.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "sim/training/report.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;

namespace {

bool ends_with(const std::string& s, const std::string& end) {
  return s.size() >= end.size() && s.compare(s.size() - end.size(), end.size(), end) == 0;
}

// The file's bytes, or nullopt when it does not exist; throws on another error.
std::optional<std::string> read_bytes(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  }
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

std::string content_version(const std::string& bytes) {
  uint64_t h = 14695981039346656037ull;  // FNV-1a 64 offset basis
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;  // FNV prime
  }
  char out[17];
  std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(h));
  return out;
}

bool valid_design_name(const std::string& name, const std::string& extension) {
  if (name.size() <= extension.size() || name.size() > 128 || name[0] == '.' || !ends_with(name, extension)) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
           c == '-';
  });
}

std::vector<std::string> DesignFolder::list(const std::string& extension) const {
  std::vector<std::string> out;
  std::error_code ec;
  if (dir_.empty() || !fs::is_directory(dir_, ec)) return out;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string name = e.path().filename().string();
    if (e.is_regular_file(ec) && valid_design_name(name, extension)) out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string DesignFolder::path(const std::string& name) const { return (fs::path(dir_) / name).string(); }

DesignText DesignFolder::read(const std::string& name) const {
  const std::string p = path(name);
  const auto bytes = read_bytes(p);
  if (!bytes) throw std::runtime_error(p + ": cannot open: " + std::strerror(ENOENT));
  return {*bytes, content_version(*bytes)};
}

SaveOutcome DesignFolder::save(const std::string& name, const std::string& text, const std::string& expected_version) {
  if (dir_.empty()) throw std::runtime_error("no designs folder (rise-instructor serve --designs DIR)");
  const std::lock_guard<std::mutex> lock(save_mutex_);
  const std::string p = path(name);
  const auto now = read_bytes(p);
  const std::string on_disk = now ? content_version(*now) : "";
  if (on_disk != expected_version) return {SaveStatus::Conflict, on_disk};
  // Through a link to the file it names (a link into a checkout stays a link),
  // and with the file's permissions (the temporary is made 0644).
  std::error_code ec;
  const std::string target = fs::is_symlink(p, ec) ? fs::canonical(p).string() : p;
  const auto perms = now ? std::optional<fs::perms>(fs::status(target).permissions()) : std::nullopt;
  sim::training::write_file_atomically(target, text);
  if (perms) fs::permissions(target, *perms, ec);
  return {SaveStatus::Saved, content_version(text)};
}

}  // namespace rise::instructor
