// rise-instructor serve started as a user starts it: a busy --listen address
// or a malformed one ends the program with one line naming it and exit
// status 2, and a server already there keeps every request.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "process/child_process.hpp"
#include "msgs/command_auth.hpp"
#include "tests/process_support.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using rise::process::ChildProcess;
using rise::instructor_test::free_port;
using rise::instructor_test::kLcm;

namespace {
using rise::test::read_file;
using rise::test::wait_until;

const std::string kBin = std::string(RISE_BINARY_DIR) + "/bin";

// The pages and the key a server needs, in a folder of its own.
struct ServeDir {
  fs::path dir;
  ServeDir() {
    char tmpl[] = "/tmp/rise-serve-test-XXXXXX";
    dir = ::mkdtemp(tmpl);
    fs::create_directories(dir / "www");
    std::ofstream(dir / "www" / "index.html") << "<!doctype html><title>console</title>";
    rise::msgs::write_new_instructor_key((dir / "instructor.key").string());
  }
  ~ServeDir() { fs::remove_all(dir); }
  std::vector<std::string> argv(const std::string& listen, const std::string& token) const {
    return {kBin + "/rise-instructor", "serve", "--listen", listen, "--token", token, "--lcm", kLcm,
            "--web-dir", (dir / "www").string(), "--instructor-key", (dir / "instructor.key").string()};
  }
};

size_t count_of(const std::string& text, const std::string& part) {
  size_t n = 0;
  for (size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}
}  // namespace

TEST_CASE("a second rise-instructor serve on a busy address exits 2 with one line while the first serves",
          "[instructor]") {
  ServeDir d;
  const std::string address = "127.0.0.1:" + std::to_string(free_port());
  ChildProcess first(d.argv(address, "tok-first"), (d.dir / "first.log").string());
  httplib::Client http("127.0.0.1", std::stoi(address.substr(address.rfind(':') + 1)));
  http.set_connection_timeout(0, 200'000);
  const auto status = [&http](const std::string& token) {
    const auto r = http.Get("/api/world", {{"X-Rise-Token", token}});
    return r ? r->status : -1;
  };
  REQUIRE(wait_until([&] { return status("tok-first") == 200 || !first.running(); }, 20000));
  REQUIRE(first.running());

  ChildProcess second(d.argv(address, "tok-second"), (d.dir / "second.log").string());
  CHECK(second.wait_for(10000) == 2);
  const std::string log = read_file(d.dir / "second.log");
  CAPTURE(log);
  CHECK(count_of(log, "[error]") == 1);
  CHECK(count_of(log, "[error] " + address + ": address in use\n") == 1);

  // With SO_REUSEPORT the kernel would have handed some connections to the second.
  for (int i = 0; i < 20; ++i) CHECK(status("tok-first") == 200);
  CHECK(first.running());
  CHECK(first.stop() == 0);
}

TEST_CASE("rise-instructor serve refuses a malformed --listen with one line naming it and exits 2", "[instructor]") {
  struct Bad {
    const char* listen;
    const char* why;
  };
  const auto bad = GENERATE(values<Bad>({{"127.0.0.1:abc", "port 'abc' is not a number 1..65535"},
                                         {"127.0.0.1:99999", "port '99999' is not a number 1..65535"},
                                         {"127.0.0.1:80x", "port '80x' is not a number 1..65535"},
                                         {":8080", "missing host (HOST:PORT)"}}));
  CAPTURE(bad.listen);
  ServeDir d;
  ChildProcess serve(d.argv(bad.listen, "tok"), (d.dir / "serve.log").string());
  CHECK(serve.wait_for(10000) == 2);
  const std::string log = read_file(d.dir / "serve.log");
  CAPTURE(log);
  CHECK(count_of(log, "\n") == 1);
  CHECK(count_of(log, "[error] --listen '" + std::string(bad.listen) + "': " + bad.why + "\n") == 1);
}
