#pragma once

// What the programs run in the vcan VM (run_in_vcan_vm.sh) share: child
// processes (can-utils, busybox applets, rise-panel) waited on through a
// pidfd so that no test sleeps, a pipe to read their output, and an
// interface brought back up when a test ends early.

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace rise::test::vm {

/// How long a peer may take under TCG.
inline constexpr int kChildTimeoutMs = 10000;

/// A child process (posix_spawnp, so PATH finds busybox applets and
/// can-utils), waited on through a pidfd so that no test sleeps.
class Child {
 public:
  /// stdout_fd, stderr_fd: the child's stdout and stderr (-1: inherit).
  explicit Child(std::vector<std::string> args, int stdout_fd = -1, int stderr_fd = -1) : args_(std::move(args)) {
    std::vector<char*> argv;
    for (std::string& a : args_) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    ::posix_spawn_file_actions_init(&actions);
    ::posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    if (stdout_fd >= 0) ::posix_spawn_file_actions_adddup2(&actions, stdout_fd, 1);
    if (stderr_fd >= 0) ::posix_spawn_file_actions_adddup2(&actions, stderr_fd, 2);
    const int err = ::posix_spawnp(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    ::posix_spawn_file_actions_destroy(&actions);
    if (err != 0) pid_ = -1;
  }
  ~Child() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  bool started() const { return pid_ > 0; }
  /// Sends a signal (no-op once it was waited for).
  void signal(int sig) {
    if (pid_ > 0) ::kill(pid_, sig);
  }

  /// Exit status once the child exited within timeout_ms; -1 if it did not
  /// (it is then killed), -2 if it died of a signal.
  int wait_exit(int timeout_ms) {
    if (pid_ <= 0) return -1;
    const int pidfd = static_cast<int>(::syscall(SYS_pidfd_open, pid_, 0));
    if (pidfd >= 0) {
      pollfd p{pidfd, POLLIN, 0};
      const int ready = ::poll(&p, 1, timeout_ms);
      ::close(pidfd);
      if (ready <= 0) return -1;  // destructor kills it
    }
    int status = 0;
    if (::waitpid(pid_, &status, 0) != pid_) return -1;
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -2;
  }

 private:
  std::vector<std::string> args_;
  pid_t pid_ = -1;
};

/// Runs a command to its end; its exit status, or -1 when it hung.
inline int run(std::vector<std::string> args, int timeout_ms = kChildTimeoutMs) {
  Child child(std::move(args));
  REQUIRE(child.started());
  return child.wait_exit(timeout_ms);
}

/// Whether a CAN_RAW socket is bound to `iface` in one of the kernel's
/// receive lists (/proc/net/can/rcvlist_LIST: "all" holds sockets without
/// filters, "sff" and "fil" those with an id:mask filter).
inline bool can_receiver_on(const std::string& iface, const std::vector<std::string>& lists) {
  bool found = false;
  for (const std::string& list : lists) {
    std::FILE* f = std::fopen(("/proc/net/can/rcvlist_" + list).c_str(), "r");
    if (!f) continue;
    char line[256];
    while (std::fgets(line, sizeof line, f)) {
      const std::string l(line);
      if (l.find(iface) != std::string::npos && l.find("no entry") == std::string::npos) found = true;
    }
    std::fclose(f);
  }
  return found;
}

/// Until a CAN_RAW socket is bound to `iface` (can_receiver_on), at most timeout_ms.
inline bool wait_for_can_receiver(const std::string& iface, const std::vector<std::string>& lists,
                                  int timeout_ms = kChildTimeoutMs) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!can_receiver_on(iface, lists))
    if (std::chrono::steady_clock::now() >= deadline) return false;
    else std::this_thread::yield();
  return true;
}

/// Brings an interface back up when a test that took it down ends early.
class LinkUpGuard {
 public:
  explicit LinkUpGuard(std::string iface) : iface_(std::move(iface)) {}
  ~LinkUpGuard() { run_noexcept({"ip", "link", "set", iface_, "up"}); }
  LinkUpGuard(const LinkUpGuard&) = delete;
  LinkUpGuard& operator=(const LinkUpGuard&) = delete;

 private:
  static void run_noexcept(std::vector<std::string> args) {
    Child child(std::move(args));
    child.wait_exit(kChildTimeoutMs);
  }
  std::string iface_;
};

/// A pipe whose read end the test polls; both ends close on destruction.
struct Pipe {
  int read_fd = -1;
  int write_fd = -1;
  Pipe() {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) == 0) {
      read_fd = fds[0];
      write_fd = fds[1];
    }
  }
  ~Pipe() {
    close_write();
    if (read_fd >= 0) ::close(read_fd);
  }
  Pipe(const Pipe&) = delete;
  Pipe& operator=(const Pipe&) = delete;
  void close_write() {
    if (write_fd >= 0) ::close(write_fd);
    write_fd = -1;
  }
};

/// Everything readable on fd within timeout_ms (until EOF or a pause).
inline std::string read_available(int fd, int timeout_ms) {
  std::string text;
  pollfd p{fd, POLLIN, 0};
  while (::poll(&p, 1, timeout_ms) > 0) {
    char buffer[512];
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n <= 0) break;
    text.append(buffer, static_cast<size_t>(n));
    timeout_ms = 0;
  }
  return text;
}

}  // namespace rise::test::vm
