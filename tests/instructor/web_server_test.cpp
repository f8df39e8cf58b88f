// rise::instructor::WebServer in this process, over real LCM and HTTP on
// loopback: the token, the world geometry, the SSE stream of LCM traffic,
// signed fault commands and the virtual panel's PanelState.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include "instructor/web_server.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/command_auth.hpp"
#include "rise_msgs/TaskStatus.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;

namespace {
struct ServerFixture {
  fs::path dir;
  rise::instructor::WebServerSettings settings;
  std::string id = "web" + std::to_string(::getpid());

  ServerFixture() {
    char tmpl[] = "/tmp/rise-web-test-XXXXXX";
    dir = ::mkdtemp(tmpl);
    fs::create_directories(dir / "www");
    std::ofstream(dir / "www" / "index.html") << "<!doctype html><title>console</title>";
    fs::create_directories(dir / "reports" / "run1");
    std::ofstream(dir / "reports" / "run1" / "training.html") << "<html>report</html>";
    rise::msgs::write_new_instructor_key((dir / "instructor.key").string());
    settings.port = 0;
    settings.token = "tok-" + id;
    settings.web_dir = (dir / "www").string();
    settings.world_file = std::string(RISE_SOURCE_DIR) + "/sim/worlds/building.yaml";
    settings.robot_file = std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml";
    settings.reports_dir = (dir / "reports").string();
    settings.panel_file = std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml";
    settings.instructor_key_file = (dir / "instructor.key").string();
    fs::create_directories(dir / "scenarios");
    std::ofstream(dir / "scenarios" / "stuck.yaml")
        << "scenario: stuck-stick\nseed: 3\nfaults:\n  - {id: stuck, kind: stuck_at, target: drive_y, value: 0.4, at: 0.0, duration: 60}\n";
    std::ofstream(dir / "scenarios" / "broken.yaml") << "scenario: broken\nfaults:\n  - {id: x, kind: stuck_at, at: nope}\n";
    settings.scenarios_dir = (dir / "scenarios").string();
    settings.scenario_program = std::string(RISE_BINARY_DIR) + "/bin/rise-instructor";
  }
  ~ServerFixture() { fs::remove_all(dir); }
  httplib::Headers auth() const { return {{"X-Rise-Token", settings.token}}; }
};
}  // namespace

TEST_CASE("the web server answers only requests that carry its token", "[instructor]") {
  ServerFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  SECTION("no token, a wrong one, or one of another length: 401") {
    auto r = http.Get("/api/world");
    REQUIRE(r);
    CHECK(r->status == 401);
    CHECK(http.Get("/?token=tok-wrong")->status == 401);
    CHECK(http.Get("/api/world", {{"X-Rise-Token", f.settings.token + "x"}})->status == 401);
    CHECK(http.Get("/index.html")->status == 401);
  }
  SECTION("the token as query, header, bearer or the cookie the query set") {
    auto r = http.Get("/?token=" + f.settings.token);
    REQUIRE(r);
    CHECK(r->status == 200);
    CHECK(r->body.find("console") != std::string::npos);
    const std::string cookie = r->get_header_value("Set-Cookie");
    CHECK(cookie.find("HttpOnly") != std::string::npos);
    CHECK(http.Get("/index.html", {{"Cookie", cookie.substr(0, cookie.find(';'))}})->status == 200);
    CHECK(http.Get("/api/world", f.auth())->status == 200);
    CHECK(http.Get("/api/world", {{"Authorization", "Bearer " + f.settings.token}})->status == 200);
  }
  SECTION("the world geometry comes from the world file") {
    const auto world = parse_json(http.Get("/api/world", f.auth())->body);
    CHECK(world["name"].asString() == "building");
    std::map<std::string, int> kinds;
    for (const auto& b : world["boxes"]) kinds[b["kind"].asString()]++;
    CHECK(kinds["wall"] > 4);
    CHECK(kinds["door"] >= 1);
    CHECK(kinds["stairs"] > 1);
    CHECK(world["regions"].size() >= 1);
    CHECK(world["objects"].size() >= 1);
    // The robot file's chassis and its camera mount (skid4: "front", 0.41 m ahead, 10° down).
    CHECK(world["robot"]["chassis_size"].size() == 3);
    REQUIRE(world["robot"]["cameras"].size() == 1);
    CHECK(world["robot"]["cameras"][0]["name"].asString() == "front");
    CHECK(world["robot"]["cameras"][0]["position"][0].asDouble() == Approx(0.41));
    CHECK(world["robot"]["cameras"][0]["rpy"][1].asDouble() == Approx(10.0 * M_PI / 180.0));
  }
  SECTION("reports are listed and served; nothing outside the folder") {
    const auto list = parse_json(http.Get("/api/reports", f.auth())->body);
    REQUIRE(list.size() == 1);
    CHECK(list[0]["url"].asString() == "/reports/run1/training.html");
    CHECK(http.Get("/reports/run1/training.html", f.auth())->body == "<html>report</html>");
    CHECK(http.Get("/reports/../instructor.key", f.auth())->status != 200);
    // Only reports: another file in the folder is not served.
    std::ofstream(f.dir / "reports" / "secret.key") << "00";
    CHECK(http.Get("/reports/secret.key", f.auth())->status == 404);
    CHECK(http.Get("/reports/run1/missing.html", f.auth())->status == 404);
  }
  server.stop();
}

TEST_CASE("a second web server on a busy address fails with 'address in use' while the first serves",
          "[instructor]") {
  ServerFixture f;
  rise::instructor::WebServer first(f.settings);
  first.start();
  rise::instructor::WebServerSettings busy = f.settings;
  busy.port = first.port();
  busy.token = "tok-second-" + f.id;
  rise::instructor::WebServer second(busy);
  CHECK_THROWS_WITH(second.start(), "127.0.0.1:" + std::to_string(first.port()) + ": address in use");
  // With SO_REUSEPORT the kernel would hand some connections to the second, which wants its own token.
  httplib::Client http("127.0.0.1", first.port());
  for (int i = 0; i < 20; ++i) {
    const auto r = http.Get("/api/world", f.auth());
    REQUIRE(r);
    CHECK(r->status == 200);
  }
  first.stop();
}

TEST_CASE("the web server streams the latest LCM messages of every trainee over SSE", "[instructor]") {
  ServerFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  TraineePeer peer(f.id);
  REQUIRE(peer.good());
  std::atomic<bool> seen{false};
  std::atomic<int> pushes{0};
  std::string first_robot;
  std::thread reader([&] {
    httplib::Client http("127.0.0.1", server.port());
    http.set_read_timeout(10, 0);
    std::string buffer;
    http.Get("/api/stream", f.auth(), [&](const char* data, size_t n) {
      buffer.append(data, n);
      for (std::size_t end; (end = buffer.find("\n\n")) != std::string::npos; buffer.erase(0, end + 2)) {
        pushes++;
        const auto u = parse_json(buffer.substr(6, end - 6));
        const auto& c = u["channels"][rise::msgs::robot_state_channel(f.id)];
        if (!c.isNull() && first_robot.empty()) {
          first_robot = c["value"]["robot_id"].asString() + " " + std::to_string(c["value"]["position"][0].asDouble());
          seen = true;
        }
      }
      return !seen;
    });
  });
  rise_msgs::RobotState r{};
  r.robot_id = f.id;
  r.position_m[0] = 1.25;
  r.orientation_wxyz[0] = 1.0;
  // Publish until the stream has carried it (the subscriber may join late).
  const bool ok = peer.wait_until([&] { return seen.load(); }, 10000,
                                  [&] { peer.lcm().publish(rise::msgs::robot_state_channel(f.id), &r); });
  reader.join();
  REQUIRE(ok);
  CHECK(first_robot == f.id + " 1.250000");
  const auto trainees = parse_json(httplib::Client("127.0.0.1", server.port()).Get("/api/trainees", f.auth())->body);
  bool listed = false;
  for (const auto& t : trainees) listed |= t["id"].asString() == f.id && t["robot_state"]["position"][0].asDouble() == 1.25;
  CHECK(listed);
  SECTION("training progress: the latest TaskStatus per trainee") {
    rise_msgs::TaskStatus s{};
    s.trainee_id = f.id;
    s.task = "approach_object";
    s.state = "running";
    s.score = 7;
    const auto task_listed = [&] {
      const auto list = parse_json(httplib::Client("127.0.0.1", server.port()).Get("/api/trainees", f.auth())->body);
      for (const auto& t : list)
        if (t["id"].asString() == f.id && t["task_status"]["task"].asString() == "approach_object")
          return t["task_status"]["score"].asInt() == 7;
      return false;
    };
    CHECK(peer.wait_until(task_listed, 5000, [&] { peer.lcm().publish(rise::msgs::task_status_channel(f.id), &s); }));
  }
  server.stop();
}

TEST_CASE("the web server keeps answering while many pages hold their streams open", "[instructor]") {
  ServerFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  TraineePeer peer(f.id);
  // 20 streams (more than cpp-httplib's default 8 request threads), each until it has one push.
  std::atomic<int> opened{0}, closed{0};
  std::atomic<bool> done{false};
  std::vector<std::thread> readers;
  for (int i = 0; i < 20; ++i)
    readers.emplace_back([&] {
      httplib::Client http("127.0.0.1", server.port());
      http.set_read_timeout(10, 0);
      bool counted = false;
      http.Get("/api/stream", f.auth(), [&](const char*, size_t) {
        if (!counted) opened++;
        counted = true;
        return !done.load();
      });
      closed++;
    });
  rise_msgs::RobotState r{};
  r.robot_id = f.id;
  r.orientation_wxyz[0] = 1.0;
  const bool all_open = peer.wait_until([&] { return opened.load() == 20; }, 10000,
                                        [&] { peer.lcm().publish(rise::msgs::robot_state_channel(f.id), &r); });
  // With every stream open, an ordinary request is still answered.
  httplib::Client http("127.0.0.1", server.port());
  const auto answer = http.Get("/api/world", f.auth());
  done = true;
  // Each stream ends at its next push.
  CHECK(peer.wait_until([&] { return closed.load() == 20; }, 10000,
                        [&] { peer.lcm().publish(rise::msgs::robot_state_channel(f.id), &r); }));
  for (auto& t : readers) t.join();
  CHECK(all_open);
  REQUIRE(answer);
  CHECK(answer->status == 200);
  server.stop();
}

TEST_CASE("a fault button publishes a FaultCommand signed with the instructor key", "[instructor]") {
  ServerFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  TraineePeer peer(f.id);
  httplib::Client http("127.0.0.1", server.port());
  rise::msgs::CommandVerifier verifier(rise::msgs::load_instructor_key(f.settings.instructor_key_file));
  SECTION("a preset is injected, then cleared") {
    auto r = http.Post("/api/fault/inject", f.auth(), R"({"trainee":")" + f.id + R"(","fault":"stick-stuck"})",
                       "application/json");
    REQUIRE(r);
    CHECK(r->status == 200);
    REQUIRE(peer.wait_until([&] { return peer.faults.size() == 1; }, 5000));
    const auto& c = peer.faults[0];
    CHECK(c.action == "inject");
    CHECK(c.kind == "stuck_at");
    CHECK(c.target == "drive_y");
    CHECK(c.value == Approx(0.6));
    CHECK(c.trainee_id == f.id);
    CHECK(c.signature_len == 32);
    CHECK(verifier.check(c, rise::msgs::wall_us()) == rise::msgs::Verdict::Accepted);
    CHECK(verifier.check(c, rise::msgs::wall_us()) == rise::msgs::Verdict::Replayed);
    REQUIRE(http.Post("/api/fault/clear", f.auth(), R"({"trainee":")" + f.id + R"(","fault":"*"})", "application/json")
                ->status == 200);
    REQUIRE(peer.wait_until([&] { return peer.faults.size() == 2; }, 5000));
    CHECK(peer.faults[1].action == "clear");
    CHECK(peer.faults[1].fault_id.empty());
    CHECK(verifier.check(peer.faults[1], rise::msgs::wall_us()) == rise::msgs::Verdict::Accepted);
  }
  SECTION("an unknown preset without a kind, or a bad trainee id, is refused") {
    auto r = http.Post("/api/fault/inject", f.auth(), R"({"trainee":")" + f.id + R"(","fault":"nope"})",
                       "application/json");
    CHECK(r->status == 400);
    CHECK(r->body.find("no such preset") != std::string::npos);
    CHECK(http.Post("/api/fault/inject", f.auth(), R"({"trainee":"a/b","fault":"stick-stuck"})", "application/json")
              ->status == 400);
    CHECK(http.Post("/api/fault/inject", f.auth(), "{not json", "application/json")->status == 400);
  }
  server.stop();
}

TEST_CASE("the web server refuses a push rate under 20 Hz, an empty token and a missing page folder", "[instructor]") {
  ServerFixture f;
  auto s = f.settings;
  s.push_hz = 10.0;
  CHECK_THROWS_WITH(rise::instructor::WebServer(s), Catch::Contains("push_hz must be at least 20"));
  s = f.settings;
  s.token.clear();
  CHECK_THROWS_WITH(rise::instructor::WebServer(s), Catch::Contains("a token is required"));
  s = f.settings;
  s.web_dir = (f.dir / "nowhere").string();
  CHECK_THROWS_WITH(rise::instructor::WebServer(s), Catch::Contains("no index.html"));
}

TEST_CASE("without an instructor key the fault buttons are refused", "[instructor]") {
  ServerFixture f;
  f.settings.instructor_key_file.clear();
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  auto r = http.Post("/api/fault/inject", f.auth(), R"({"trainee":"t1","fault":"stick-stuck"})", "application/json");
  CHECK(r->status == 503);
  server.stop();
}

TEST_CASE("the server publishes a virtual panel's PanelState and fails it safe when the page stops", "[instructor]") {
  ServerFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  TraineePeer peer(f.id);
  httplib::Client http("127.0.0.1", server.port());
  const std::string body =
      R"({"axes":{"drive_y":0.8},"buttons":{"deadman":true,"estop":false},"switches":{"mode":"drive","speed":"fast"}})";
  SECTION("bad input is refused with what is wrong") {
    auto r = http.Post("/api/virtual/" + f.id, f.auth(), R"({"axes":{"warp":1}})", "application/json");
    CHECK(r->status == 400);
    CHECK(r->body.find("axis 'warp'") != std::string::npos);
  }
  SECTION("a station whose PanelState another process publishes gets no virtual panel") {
    rise_msgs::PanelState daemon{};
    daemon.trainee_id = f.id;
    daemon.publisher.session_id = 12345;
    daemon.publisher.program = "rise-hild";
    daemon.publisher.host = "lab3";
    daemon.publisher.pid = 4242;
    // The server has heard the daemon once its trainee list names it.
    const auto heard = [&] {
      const auto r = http.Get("/api/trainees", f.auth());
      return r && r->body.find("\"pid\":4242") != std::string::npos;
    };
    REQUIRE(peer.wait_until(heard, 5000, [&] { peer.lcm().publish(rise::msgs::panel_state_channel(f.id), &daemon); }));
    const auto r = http.Post("/api/virtual/" + f.id, f.auth(), body, "application/json");
    const std::string answer = r->body;
    INFO(answer);
    CHECK(r->status == 409);
    CHECK(answer.find("rise/" + f.id + "/panel_state is already published by rise-hild pid 4242 on lab3") !=
          std::string::npos);
  }
  SECTION("a page sending, then stopping") {
    const auto driving = [&] {
      return !peer.panels.empty() && !peer.panels.back().failsafe && peer.panels.back().deadman;
    };
    const bool drove = peer.wait_until(driving, 5000,
                            [&] { REQUIRE(http.Post("/api/virtual/" + f.id, f.auth(), body, "application/json")->status == 204); });
    INFO("last: " << (peer.panels.empty() ? std::string("none") : peer.panels.back().failsafe_reason));
    REQUIRE(drove);
    const auto& on = peer.panels.back();
    CHECK(on.sources[0].connected);
    REQUIRE(on.axes.size() >= 2);
    CHECK(on.axes[1].name == "drive_y");
    CHECK(on.axes[1].value == Approx((0.8 - 0.05) / 0.95).margin(1e-3));
    const std::size_t last_driving = peer.panels.size() - 1;
    // No more updates: the next states turn failsafe by the timeout, at the safe values.
    REQUIRE(peer.wait_until([&] { return peer.panels.back().failsafe; }, 5000));
    const auto& off = peer.panels.back();
    CHECK_FALSE(off.deadman);
    CHECK(off.axes[1].value == 0.0f);
    CHECK(off.sources[0].stale);
    CHECK(off.failsafe_reason.find("virtual: stale") != std::string::npos);
    // Published at the panel's rate all along: the states in between came every ~10 ms.
    const auto gap_us = off.utime - peer.panels[last_driving].utime;
    INFO("failsafe " << gap_us / 1000 << " ms after the last driving state");
    CHECK(peer.panels.size() - last_driving > 1);
    SECTION("a fault button's input fault reaches the virtual panel; an unsigned one is reported") {
      const auto post = [&] { REQUIRE(http.Post("/api/virtual/" + f.id, f.auth(), body, "application/json")->status == 204); };
      REQUIRE(http.Post("/api/fault/inject", f.auth(), R"({"trainee":")" + f.id + R"(","fault":"stick-stuck"})",
                        "application/json")->status == 200);
      const auto has = [&](const std::string& text) {
        if (peer.panels.empty()) return false;
        const auto& a = peer.panels.back().active_faults;
        return std::any_of(a.begin(), a.end(), [&](const std::string& s) { return s.rfind(text, 0) == 0; });
      };
      REQUIRE(peer.wait_until([&] { return has("stick-stuck: stuck_at drive_y") && !peer.panels.back().failsafe; }, 5000, post));
      CHECK(peer.panels.back().axes[1].value == Approx((0.6 - 0.05) / 0.95).margin(1e-3));
      rise_msgs::FaultCommand unsigned_command{};
      unsigned_command.trainee_id = f.id;
      unsigned_command.action = "clear";
      unsigned_command.issuer = "trainee";
      // Sent again every 200 ms until reported: one datagram can be lost under load.
      auto next_send = std::chrono::steady_clock::now();
      REQUIRE(peer.wait_until([&] { return has("rejected: unsigned"); }, 5000, [&] {
        post();
        if (std::chrono::steady_clock::now() < next_send) return;
        peer.lcm().publish(rise::msgs::fault_command_channel(f.id), &unsigned_command);
        next_send += std::chrono::milliseconds(200);
      }));
      CHECK(has("rejected: unsigned"));
    }
    SECTION("the page's goodbye disconnects the source") {
      REQUIRE(http.Post("/api/virtual/" + f.id, f.auth(), body, "application/json")->status == 204);
      REQUIRE(http.Post("/api/virtual/" + f.id + "/close", f.auth(), "", "text/plain")->status == 204);
      peer.panels.clear();
      REQUIRE(peer.wait_until([&] { return !peer.panels.empty() && !peer.panels.back().sources[0].connected; }, 5000));
      CHECK(peer.panels.back().failsafe);
    }
    SECTION("a request the page sent before its goodbye, arriving after it, does not revive the panel") {
      const std::string page = "/api/virtual/" + f.id + "?page=0a1b2c3d";
      REQUIRE(http.Post(page, f.auth(), body, "application/json")->status == 204);
      REQUIRE(http.Post("/api/virtual/" + f.id + "/close?page=0a1b2c3d", f.auth(), "", "text/plain")->status == 204);
      // The overtaken update: refused as from a closed page.
      CHECK(http.Post(page, f.auth(), body, "application/json")->status == 410);
      peer.panels.clear();
      REQUIRE(peer.wait_until([&] { return peer.panels.size() >= 5; }, 5000));
      for (const auto& p : peer.panels) CHECK(p.failsafe);
      // The same trainee's next page (another load) drives again.
      REQUIRE(peer.wait_until([&] { return !peer.panels.back().failsafe; }, 5000, [&] {
        REQUIRE(http.Post("/api/virtual/" + f.id + "?page=99aa", f.auth(), body, "application/json")->status == 204);
      }));
      CHECK(http.Post("/api/virtual/" + f.id + "?page=no/slash", f.auth(), body, "application/json")->status == 400);
    }
  }
  server.stop();
}

TEST_CASE("scenario control runs a scenario file against a trainee and stops it", "[instructor]") {
  ServerFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  TraineePeer peer(f.id);
  httplib::Client http("127.0.0.1", server.port());
  const auto list = parse_json(http.Get("/api/scenarios", f.auth())->body);
  CHECK(list["enabled"].asBool());
  REQUIRE(list["files"].size() == 2);
  CHECK(list["files"][0]["file"].asString() == "broken.yaml");
  CHECK(list["files"][0]["error"].asString().find("broken.yaml:") != std::string::npos);
  CHECK(list["files"][1]["name"].asString() == "stuck-stick");
  SECTION("a bad file is refused") {
    CHECK(http.Post("/api/scenario/start", f.auth(), R"({"trainee":")" + f.id + R"(","file":"broken.yaml"})",
                    "application/json")->status == 400);
    CHECK(http.Post("/api/scenario/start", f.auth(), R"({"trainee":")" + f.id + R"(","file":"../x.yaml"})",
                    "application/json")->status == 400);
  }
  SECTION("start: its fault is injected, signed; stop: its auto_clear fault is cleared") {
    auto r = http.Post("/api/scenario/start", f.auth(), R"({"trainee":")" + f.id + R"(","file":"stuck.yaml","seed":11})",
                       "application/json");
    REQUIRE(r->status == 200);
    CHECK(parse_json(r->body)["seed"].asUInt64() == 11);
    REQUIRE(peer.wait_until([&] { return !peer.faults.empty(); }, 10000));
    CHECK(peer.faults[0].action == "inject");
    CHECK(peer.faults[0].fault_id == "stuck");
    CHECK(peer.faults[0].kind == "stuck_at");
    rise::msgs::CommandVerifier verifier(rise::msgs::load_instructor_key(f.settings.instructor_key_file));
    CHECK(verifier.check(peer.faults[0], rise::msgs::wall_us()) == rise::msgs::Verdict::Accepted);
    CHECK(parse_json(http.Get("/api/scenarios", f.auth())->body)["running"].isMember(f.id));
    REQUIRE(http.Post("/api/scenario/stop", f.auth(), R"({"trainee":")" + f.id + R"("})", "application/json")->status ==
            200);
    REQUIRE(peer.wait_until([&] { return peer.faults.size() >= 2; }, 10000));
    CHECK(peer.faults.back().action == "clear");
    CHECK(peer.faults.back().fault_id == "stuck");
    CHECK_FALSE(parse_json(http.Get("/api/scenarios", f.auth())->body)["running"].isMember(f.id));
  }
  server.stop();
}
