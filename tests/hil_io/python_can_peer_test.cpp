#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "test_support.hpp"

extern char** environ;

using namespace rise::hil::io;
using rise::hil::io::test::make_frame;

namespace {

// Debian's interpreter, where python3-can lives; the python3 first on PATH
// may be another installation without it.
constexpr const char* kPython = "/usr/bin/python3";

// A child process started with posix_spawn, stdout and stderr to a file;
// killed by PID if still running when it goes out of scope.
class Child {
 public:
  Child(std::vector<std::string> args, const std::string& output_path) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    // Drop variables of other Python installations (pyenv shims set them).
    std::vector<char*> env;
    for (char** e = environ; *e != nullptr; ++e) {
      if (std::strncmp(*e, "PYTHONHOME=", 11) != 0 && std::strncmp(*e, "PYTHONPATH=", 11) != 0) {
        env.push_back(*e);
      }
    }
    env.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, output_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), env.data()) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Child() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  bool started() const { return pid_ > 0; }
  /// True once the child has exited; exit_code() is then valid.
  bool poll_exit() {
    if (exited_ || pid_ <= 0) return exited_;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      exited_ = true;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    return exited_;
  }
  int exit_code() const { return exit_code_; }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = -1;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string temp_path(const char* name) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir != nullptr ? dir : "/tmp") + "/" + name + "." + std::to_string(::getpid());
}

size_t count_lines(const std::string& text, const std::string& line) {
  size_t count = 0;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) count += l == line ? 1 : 0;
  return count;
}

}  // namespace

TEST_CASE("python-can's socketcand client talks to the listen server both ways", "[hil_io]") {
  if (::access(kPython, X_OK) != 0) {
    WARN("skipped: " << kPython << " is not installed");
    return;
  }
  const std::string output = temp_path("rise_hil_io_python_can");
  {
    Child probe({kPython, "-c", "import can"}, output);
    REQUIRE(probe.started());
    REQUIRE(rise::hil::io::test::wait_until([&] { return probe.poll_exit(); }, std::chrono::seconds(30)));
    if (probe.exit_code() != 0) {
      WARN("skipped: python-can is not importable by " << kPython << ": " << read_file(output));
      return;
    }
  }

  auto server = open_can_bus("socketcand+listen://127.0.0.1:0/can0");
  const uint16_t port = listening_port(*server);
  REQUIRE(port != 0);
  Child peer({kPython, std::string(RISE_SOURCE_DIR) + "/tests/hil_io/python_can_socketcand_peer.py",
              "127.0.0.1", std::to_string(port)},
             output);
  REQUIRE(peer.started());

  // Until the script ends: collect what it sends, and keep offering it the
  // known frame (receive()'s timeout paces the loop).
  const CanFrame known = make_frame(0x321, {1, 2, 3, 4, 5, 6, 7, 8});
  std::vector<CanFrame> from_python;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  bool exited = false;
  while (!(exited = peer.poll_exit()) && std::chrono::steady_clock::now() < deadline) {
    CanFrame got;
    if (server->receive(got, 20) == IoStatus::Ok) from_python.push_back(got);
    REQUIRE(server->send(known) == IoStatus::Ok);
  }
  CanFrame late;
  while (server->receive(late, 0) == IoStatus::Ok) from_python.push_back(late);

  const std::string printed = read_file(output);
  std::remove(output.c_str());
  INFO("python peer output:\n" << printed);
  REQUIRE(exited);  // else the Child destructor kills it by PID
  CHECK(peer.exit_code() == 0);
  // python-can 4.1 drops one character after each batch it parses, which can
  // spoil a message cut between two recv() calls: count intact frames only.
  CHECK(count_lines(printed, "RX 321 0102030405060708") >= 3);
  REQUIRE(from_python.size() == 2);
  CHECK(same_content(from_python[0], make_frame(0x123, {1, 2, 3})));
  CHECK(same_content(from_python[1], make_frame(0x1ABCDEF0, {0xDE, 0xAD}, true)));
}
