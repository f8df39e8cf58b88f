#pragma once

// A real pty pair made by Debian's socat, for the tests of serial links
// (SLCAN adapters, Modbus RTU): `socat -d -d pty,raw,echo=0,link=A
// pty,raw,echo=0,link=B`, run as a process::ChildProcess with its notices in
// a log file.

#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <string>
#include <utility>

#include "process/child_process.hpp"
#include "tests/process_support.hpp"

namespace rise::test {

constexpr const char* kSocat = "/usr/bin/socat";

inline bool have_socat() { return ::access(kSocat, X_OK) == 0; }

class SocatPtys {
 public:
  /// Links the pair at `a` and `b`; socat's log is appended to `log`. Waits
  /// (5 s at most) until socat says both links are up ("starting data
  /// transfer loop"), or gave up: ready() tells which.
  SocatPtys(std::string a, std::string b, const std::string& log)
      : a_(std::move(a)),
        b_(std::move(b)),
        log_from_(read_file(log).size()),
        socat_({kSocat, "-d", "-d", "pty,raw,echo=0,link=" + a_, "pty,raw,echo=0,link=" + b_}, log) {
    ready_ = wait_until([&] { return up(log) || !socat_.running(); }, 5000) && socat_.running();
  }
  /// The pair at DIR/a and DIR/b, the log in DIR/socat.log.
  explicit SocatPtys(const std::string& dir) : SocatPtys(dir + "/a", dir + "/b", dir + "/socat.log") {}
  ~SocatPtys() { stop(); }
  SocatPtys(const SocatPtys&) = delete;
  SocatPtys& operator=(const SocatPtys&) = delete;

  /// True once both links exist and socat is running (until stop() or crash()).
  bool ready() const { return ready_; }
  const std::string& a() const { return a_; }
  const std::string& b() const { return b_; }

  /// Ends socat with SIGTERM (the pty masters close: both ends hang up; socat
  /// removes the links) and reaps it.
  void stop() { end(SIGTERM); }
  /// Ends socat with SIGKILL, as a crash: no goodbye on the ptys.
  void crash() { end(SIGKILL); }

 private:
  bool up(const std::string& log) const {
    return read_file(log).find("starting data transfer loop", log_from_) != std::string::npos &&
           std::filesystem::exists(a_) && std::filesystem::exists(b_);
  }

  // Whatever ended socat, the links go with it, so a new pair can take the
  // paths; only once, so the old pair's destructor leaves a new pair's links.
  void end(int sig) {
    if (ended_) return;
    ended_ = true;
    socat_.signal(sig);
    socat_.stop();
    std::error_code ignored;
    std::filesystem::remove(a_, ignored);
    std::filesystem::remove(b_, ignored);
    ready_ = false;
  }

  std::string a_;
  std::string b_;
  std::size_t log_from_;  // what an earlier socat wrote to the same log
  process::ChildProcess socat_;
  bool ready_ = false;
  bool ended_ = false;
};

}  // namespace rise::test
