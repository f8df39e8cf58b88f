#include "hil/io/record_file.hpp"

#include <stdexcept>

namespace rise::hil::io {

RecordFile::RecordFile(const std::string& path, std::string_view what)
    : out_(path, std::ios::trunc), last_flush_(std::chrono::steady_clock::now()) {
  if (!out_) throw std::runtime_error(path + ": cannot create the " + std::string(what));
}

RecordFile::~RecordFile() { out_.flush(); }

bool RecordFile::write_line(std::string_view line) {
  out_.write(line.data(), static_cast<std::streamsize>(line.size()));
  out_.put('\n');
  const auto now = std::chrono::steady_clock::now();
  if (now - last_flush_ >= std::chrono::milliseconds(100)) {
    out_.flush();
    last_flush_ = now;
  }
  if (!out_) {
    ++errors_;
    out_.clear();
    return false;
  }
  ++lines_;
  return true;
}

}  // namespace rise::hil::io
