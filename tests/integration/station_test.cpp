// A new user's first hour, as processes: one publisher per station (a
// second rise-hild or rise-sim on a station is refused; two let in are
// reported by each other and shown by `rise status` and `rise-instructor
// list`), a source that is down says why, `rise status` ends when nothing
// arrives, `rise demo` reports a child that dies and takes a free station
// id, and a looped console script starts again after its final @silent.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "msgs/channels.hpp"
#include "msgs/publisher_session.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"
#include "tests/integration/integration_support.hpp"
#include "tests/process_support.hpp"

using rise::process::ChildProcess;
using rise::test::kBin;
using rise::test::kSource;
using rise::test::read_file;
using rise::test::wait_for_text;
namespace fs = std::filesystem;

namespace {
const std::string kLcm = rise::msgs::kDefaultLcmUrl;

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// A temporary folder per test case, removed at the end.
struct TempDir {
  explicit TempDir(const std::string& name)
      : path(fs::temp_directory_path() / ("rise-station-" + name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string file(const std::string& name) const { return (fs::path(path) / name).string(); }
  std::string path;
};

std::string unique_id(const std::string& stem) { return stem + std::to_string(::getpid()); }

// A rise-hild whose console never answers: it publishes failsafe PanelStates.
std::vector<std::string> lone_hild(const std::string& id, const std::string& source,
                                   std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{kBin + "/rise-hild", "--source", source, "--id", id, "--lcm", kLcm};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

// Runs a program to its end; returns its exit code and fills `output`.
int run_to_end(const std::vector<std::string>& argv, const std::string& log, std::string& output, int timeout_ms) {
  ChildProcess p(argv, log);
  const int rc = p.wait_for(timeout_ms);
  if (rc < 0) p.stop(1000);
  output = read_file(log);
  return rc;
}

uint16_t closed_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}
}  // namespace

TEST_CASE("a second rise-hild on a station refuses to start and names the first one's host and pid",
          "[integration]") {
  TempDir dir("hild-twice");
  const std::string id = unique_id("dup");
  const std::string source = "socketcand://127.0.0.1:" + std::to_string(closed_port()) + "/can0";
  ChildProcess first(lone_hild(id, source), dir.file("first.log"));
  REQUIRE(wait_for_text(dir.file("first.log"), "rise-hild ready"));
  ChildProcess second(lone_hild(id, source), dir.file("second.log"));
  CHECK(second.wait_for(10000) == 2);
  const std::string log = read_file(dir.file("second.log"));
  INFO(log);
  CHECK(log.find("rise/" + id + "/panel_state is already published by rise-hild pid " + std::to_string(first.pid()) +
                 " on " + rise::msgs::this_publisher().host) != std::string::npos);
  CHECK(log.find("--allow-duplicate-id") != std::string::npos);
  CHECK(first.running());
}

TEST_CASE("a second rise-sim on a station refuses to start", "[integration]") {
  TempDir dir("sim-twice");
  const std::string id = unique_id("dupsim");
  ChildProcess first({kBin + "/rise-sim", "--id", id, "--lcm", kLcm}, dir.file("first.log"));
  REQUIRE(wait_for_text(dir.file("first.log"), "rise-sim ready"));
  ChildProcess second({kBin + "/rise-sim", "--id", id, "--lcm", kLcm}, dir.file("second.log"));
  CHECK(second.wait_for(10000) == 2);
  const std::string log = read_file(dir.file("second.log"));
  INFO(log);
  CHECK(log.find("rise/" + id + "/robot_state is already published by rise-sim pid " + std::to_string(first.pid())) !=
        std::string::npos);
}

TEST_CASE("two publishers let onto one station report each other within a second, and rise status and "
          "rise-instructor list show both",
          "[integration]") {
  TempDir dir("hild-both");
  const std::string id = unique_id("both");
  const std::string source = "socketcand://127.0.0.1:" + std::to_string(closed_port()) + "/can0";
  ChildProcess first(lone_hild(id, source, {"--allow-duplicate-id"}), dir.file("first.log"));
  REQUIRE(wait_for_text(dir.file("first.log"), "rise-hild ready"));
  ChildProcess second(lone_hild(id, source, {"--allow-duplicate-id"}), dir.file("second.log"));
  REQUIRE(wait_for_text(dir.file("second.log"), "rise-hild ready"));
  const auto ready = std::chrono::steady_clock::now();
  const std::string channel = "another publisher on rise/" + id + "/panel_state: rise-hild pid ";
  REQUIRE(wait_for_text(dir.file("first.log"), channel + std::to_string(second.pid()), 5000));
  REQUIRE(wait_for_text(dir.file("second.log"), channel + std::to_string(first.pid()), 5000));
  const double seen_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - ready).count();
  INFO("both reported " << seen_s << " s after the second was ready");
  CHECK(seen_s < 1.0);

  std::string status;
  CHECK(run_to_end({kBin + "/rise", "status", "--id", id, "--lcm", kLcm, "--count", "1", "--every", "0.5"},
                   dir.file("status.log"), status, 10000) == 0);
  INFO(status);
  CHECK(status.find("DUPLICATE: 2 processes publish rise/" + id + "/panel_state") != std::string::npos);
  CHECK(status.find("rise-hild pid " + std::to_string(first.pid())) != std::string::npos);
  CHECK(status.find("rise-hild pid " + std::to_string(second.pid())) != std::string::npos);

  std::string list;
  CHECK(run_to_end({kBin + "/rise-instructor", "list", "--lcm", kLcm, "--wait", "1"}, dir.file("list.log"), list,
                   10000) == 0);
  INFO(list);
  CHECK(list.find("DUPLICATE: rise/" + id + "/panel_state has more than one publisher") != std::string::npos);
  CHECK(list.find("rise-hild pid " + std::to_string(first.pid())) != std::string::npos);
  CHECK(list.find("rise-hild pid " + std::to_string(second.pid())) != std::string::npos);
}

TEST_CASE("rise-hild says why a source is down, once per change, and rise status shows it", "[integration]") {
  TempDir dir("down");
  const std::string id = unique_id("down");
  SECTION("a host that does not resolve") {
    ChildProcess hild(lone_hild(id, "socketcand://nosuchhost.invalid:29536/can0"), dir.file("hild.log"));
    REQUIRE(wait_for_text(dir.file("hild.log"), "source 'console' down: "));
    std::string status;
    CHECK(run_to_end({kBin + "/rise", "status", "--id", id, "--lcm", kLcm, "--count", "1", "--every", "1.5"},
                     dir.file("status.log"), status, 10000) == 0);
    const std::string log = read_file(dir.file("hild.log"));
    INFO(log << status);
    CHECK(log.find("cannot resolve host 'nosuchhost.invalid'") != std::string::npos);
    CHECK(count_of(log, "source 'console' down: ") == 1);  // retried several times, said once
    CHECK(status.find("down: socketcand://nosuchhost.invalid:29536/can0: cannot resolve host 'nosuchhost.invalid'") !=
          std::string::npos);
    // A bus that never opened has no controller state and no frame age.
    CHECK(status.find("error-active") == std::string::npos);
    CHECK(status.find("-0.0") == std::string::npos);
    CHECK(status.find("unknown") == std::string::npos);
  }
  SECTION("a port nobody listens on") {
    const uint16_t port = closed_port();
    ChildProcess hild(lone_hild(id, "socketcand://127.0.0.1:" + std::to_string(port) + "/can0"), dir.file("hild.log"));
    REQUIRE(wait_for_text(dir.file("hild.log"), "source 'console' down: "));
    const std::string log = read_file(dir.file("hild.log"));
    INFO(log);
    CHECK(log.find("Connection refused") != std::string::npos);
  }
}

TEST_CASE("rise status ends with exit 1 when no PanelState arrives", "[integration]") {
  TempDir dir("status-none");
  const std::string id = unique_id("nosuch");
  std::string out;
  SECTION("--count") {
    CHECK(run_to_end({kBin + "/rise", "status", "--id", id, "--lcm", kLcm, "--count", "2", "--every", "0.2"},
                     dir.file("status.log"), out, 10000) == 1);
    CHECK(out.find("no PanelState on rise/" + id + "/panel_state") != std::string::npos);
  }
  SECTION("--timeout") {
    CHECK(run_to_end({kBin + "/rise", "status", "--id", id, "--lcm", kLcm, "--timeout", "0.5", "--every", "0.2"},
                     dir.file("status.log"), out, 10000) == 1);
  }
}

TEST_CASE("rise demo reports a child that exits at once, with the end of its log", "[integration]") {
  TempDir dir("demo-child");
  std::string out;
  SECTION("a console script that does not exist") {
    const auto start = std::chrono::steady_clock::now();
    CHECK(run_to_end({kBin + "/rise", "demo", "--script", "/nonexistent/drive.txt", "--log-dir", dir.path},
                     dir.file("demo.log"), out, 20000) == 1);
    const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    INFO(out);
    CHECK(out.find("rise-panel exited with status 2") != std::string::npos);
    CHECK(out.find("/nonexistent/drive.txt") != std::string::npos);
    CHECK(took_s < 10.0);  // not the 15 s start-up wait
  }
  SECTION("a busy console port") {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
    REQUIRE(::listen(fd, 4) == 0);
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    const std::string port = std::to_string(ntohs(a.sin_port));
    CHECK(run_to_end({kBin + "/rise", "demo", "--port", port, "--log-dir", dir.path}, dir.file("demo.log"), out,
                     20000) == 1);
    ::close(fd);
    INFO(out);
    CHECK(out.find("rise-panel exited with status 2") != std::string::npos);
    CHECK(out.find("127.0.0.1:" + port + ": address in use") != std::string::npos);
  }
}

TEST_CASE("rise demo takes a free station id when 'demo' is in use, and its summary is its own", "[integration]") {
  TempDir dir("demo-id");
  // Another publisher on rise/demo/panel_state, as a running demo would be.
  std::atomic<bool> publishing{true};
  std::thread other([&] {
    lcm::LCM lcm(kLcm);
    rise_msgs::PanelState m{};
    m.trainee_id = "demo";
    m.publisher = rise::msgs::this_publisher();
    while (publishing) {
      ++m.seq;
      lcm.publish("rise/demo/panel_state", &m);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  std::string out;
  const int rc = run_to_end({kBin + "/rise", "demo", "--log-dir", dir.path}, dir.file("demo.log"), out, 90000);
  publishing = false;
  other.join();
  INFO(out);
  CHECK(rc == 0);
  CHECK(out.find("station 'demo' is in use, taking 'demo-2'") != std::string::npos);
  CHECK(out.find("on rise/demo-2/*") != std::string::npos);
  CHECK(out.find("EXCEEDED") == std::string::npos);
  CHECK(out.find("result                ok") != std::string::npos);
}

TEST_CASE("a looped console script starts again after its final @silent, with every directive undone",
          "[integration]") {
  TempDir dir("loop");
  const std::string id = unique_id("loop");
  const std::string script = dir.file("loop.txt");
  std::ofstream(script) << "0.0 deadman pressed\n0.3 @status fault\n0.6 @silent\n";
  const std::string bus = "127.0.0.1:" + std::to_string(closed_port()) + "/can0";
  ChildProcess panel({kBin + "/rise-panel", "emulate", "--can", "socketcand+listen://" + bus, "--script", script,
                      "--loop"},
                     dir.file("panel.log"));
  REQUIRE(wait_for_text(dir.file("panel.log"), "rise-panel ready"));
  ChildProcess hild(lone_hild(id, "socketcand://" + bus), dir.file("hild.log"));

  // ok → failsafe (fault, then silence) → ok again, on every pass.
  struct Watch {
    std::atomic<int> recoveries{0};
    bool failsafe = true, was_failsafe_after_ok = false, seen_ok = false;
    void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) {
      if (!m->failsafe && was_failsafe_after_ok) ++recoveries;
      if (!m->failsafe) {
        seen_ok = true;
        was_failsafe_after_ok = false;
      } else if (seen_ok) {
        was_failsafe_after_ok = true;
      }
    }
  } watch;
  lcm::LCM lcm(kLcm);
  lcm.subscribe(rise::msgs::panel_state_channel(id), &Watch::on, &watch)->setQueueCapacity(1000);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  while (watch.recoveries < 2 && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(50);
  INFO(read_file(dir.file("panel.log")) << read_file(dir.file("hild.log")));
  CHECK(watch.recoveries >= 2);
  CHECK(read_file(dir.file("panel.log")).find("script restarts") != std::string::npos);
}
