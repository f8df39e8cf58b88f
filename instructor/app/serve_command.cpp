#include "instructor/app/serve_command.hpp"

#include <spdlog/spdlog.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <semaphore>
#include <sstream>

#include "process/child_process.hpp"
#include "hil/io/host_port.hpp"
#include "instructor/app/instructor_commands.hpp"
#include "instructor/web_server.hpp"
#include "msgs/command_auth.hpp"
#include "panels/data_path.hpp"
#include "msgs/publisher_session.hpp"

namespace rise::instructor {
namespace {

struct ServeOptions {
  std::string listen = "127.0.0.1:8080";
  std::string token;
  std::string token_file;
  std::string world;
  std::string robot = "sim/robots/skid4.yaml";
  std::string reports_dir;
  std::string scenarios_dir = "instructor/scenarios";
  std::string designs = "sim/training/examples";
  std::string worlds = "sim/worlds";
  std::string robots = "sim/robots";
  std::string consoles = "panels/definitions";
  std::vector<std::string> console_sources;
  std::string web_dir;
  std::string panel = "panels/definitions/rise_console.yaml";
  uint32_t virtual_timeout_ms = 200;
  double push_hz = 50.0;
  uint32_t lost_after_ms = 500;
};

std::binary_semaphore g_stop{0};

void on_signal(int) { g_stop.release(); }

std::string read_token(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file + ": cannot open: " + std::strerror(errno));
  std::string token;
  std::getline(in, token);
  while (!token.empty() && (token.back() == '\r' || token.back() == ' ')) token.pop_back();
  if (token.empty()) throw std::runtime_error(file + ":1: empty token");
  return token;
}

// A builder folder in the start-up line ("off" when there is none).
std::string off_or(const std::string& dir) { return dir.empty() ? "off" : dir; }

int serve(const ServeOptions& o) {
  WebServerSettings s;
  std::string error;
  const auto listen = hil::io::parse_host_port(o.listen, &error);
  if (!listen) throw std::runtime_error("--listen '" + o.listen + "': " + error);
  s.host = listen->host;
  s.port = listen->port;
  if (s.host != "127.0.0.1" && s.host != "localhost" && s.host != "::1")
    spdlog::warn("listening on {} — not loopback: anyone who can reach it and has the token can drive", s.host);
  if (!o.token.empty() && !o.token_file.empty()) throw std::runtime_error("give --token or --token-file, not both");
  s.token = o.token_file.empty() ? o.token : read_token(o.token_file);
  if (s.token.empty()) throw std::runtime_error("a token is required: --token T or --token-file F");
  s.web_dir = o.web_dir.empty() ? panels::find_data_file("instructor/web/dist") : o.web_dir;
  s.world_file = o.world.empty() ? "" : panels::find_data_file(o.world);
  s.robot_file = o.robot.empty() ? "" : panels::find_data_file(o.robot);
  // --lcm, --instructor-key, --issuer: rise-instructor's common options.
  const CommonOptions& common = common_options();
  s.lcm_url = common.lcm_url;
  s.issuer = common.issuer;
  s.reports_dir = o.reports_dir;
  s.scenarios_dir = o.scenarios_dir.empty() ? "" : panels::find_data_file(o.scenarios_dir);
  s.scenario_program = process::executable_dir() + "/rise-instructor";
  s.designs_dir = o.designs.empty() ? "" : panels::find_data_file(o.designs);
  if (!s.designs_dir.empty() && !std::filesystem::is_directory(s.designs_dir))
    throw std::runtime_error(s.designs_dir + ": cannot open: " +
                             std::strerror(std::filesystem::exists(s.designs_dir) ? ENOTDIR : ENOENT));
  s.worlds_dir = o.worlds.empty() ? "" : panels::find_data_file(o.worlds);
  s.robots_dir = o.robots.empty() ? "" : panels::find_data_file(o.robots);
  s.consoles_dir = o.consoles.empty() ? "" : panels::find_data_file(o.consoles);
  s.console_sources = o.console_sources;
  s.panel_file = panels::find_data_file(o.panel);
  s.virtual_timeout_ms = o.virtual_timeout_ms;
  s.push_hz = o.push_hz;
  s.lost_after_ms = o.lost_after_ms;
  s.instructor_key_file = msgs::instructor_key_path(common.key_file);
  if (s.instructor_key_file.empty()) spdlog::warn("no instructor key: the fault buttons are off (--instructor-key FILE)");

  s.on_duplicate_publisher = [](const std::string& line) { spdlog::warn("{}", line); };
  msgs::init_publisher("rise-instructor");
  WebServer server(s);
  server.start();
  spdlog::info("rise-instructor serve: http://{}/?token=… (console), /panel.html?id=ID&token=… (virtual panel), "
               "/console_builder.html, /robot_builder.html, /world_builder.html, /task_builder.html, /training.html "
               "?token=… (the builders: consoles {}, robots {}, worlds {}, tasks and trainings {}); LCM {}",
               hil::io::format_host_port(s.host, static_cast<uint16_t>(server.port())), off_or(s.consoles_dir),
               off_or(s.robots_dir), off_or(s.worlds_dir), off_or(s.designs_dir), s.lcm_url);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  g_stop.acquire();
  spdlog::info("stopping");
  server.stop();
  return 0;
}

}  // namespace

void add_serve_command(CLI::App& app) {
  auto o = std::make_shared<ServeOptions>();
  auto* cmd = app.add_subcommand("serve", "the web console (live map, 3D view, panels, faults, reports) and the "
                                          "virtual panel pages");
  cmd->add_option("--listen", o->listen, "HOST:PORT (loopback by default)")->capture_default_str();
  cmd->add_option("--token", o->token, "the token every request must carry (?token=, Bearer, X-Rise-Token)");
  cmd->add_option("--token-file", o->token_file, "read the token from the first line of this file");
  cmd->add_option("--world", o->world, "world file the map and 3D view draw (default: the built-in yard)");
  cmd->add_option("--robot", o->robot, "robot file the 3D view takes the chassis and the onboard camera from (\"\": none)")
      ->capture_default_str();
  cmd->add_option("--reports-dir", o->reports_dir, "training reports to list and serve (rise-trainer --out)");
  cmd->add_option("--scenarios-dir", o->scenarios_dir, "the scenario files the console offers (\"\": none)")
      ->capture_default_str();
  cmd->add_option("--designs", o->designs,
                  "the folder of training and task files the builder pages read and write (\"\": builders off)")
      ->capture_default_str();
  cmd->add_option("--worlds", o->worlds, "the folder of world files the Environment Builder reads and writes (\"\": off)")
      ->capture_default_str();
  cmd->add_option("--robots", o->robots, "the folder of robot files the Robot Builder reads and writes (\"\": off)")
      ->capture_default_str();
  cmd->add_option("--consoles", o->consoles,
                  "the folder of panel definitions the Console Builder reads and writes (\"\": off)")
      ->capture_default_str();
  cmd->add_option("--console-source", o->console_sources,
                  "the Console Builder's live view: each source's URL, as rise-hild --source (repeat per source)");
  cmd->add_option("--web-dir", o->web_dir, "the built pages (default: instructor/web/dist, installed or of the source tree)");
  cmd->add_option("--panel", o->panel, "console definition the virtual panel copies")->capture_default_str();
  cmd->add_option("--virtual-timeout-ms", o->virtual_timeout_ms, "a virtual panel without an update this long fails safe")
      ->capture_default_str();
  cmd->add_option("--push-hz", o->push_hz, "SSE push rate (>= 20)")->capture_default_str();
  cmd->add_option("--lost-after-ms", o->lost_after_ms, "a trainee not heard this long shows as lost")
      ->check(CLI::Range(50u, 60000u))
      ->capture_default_str();
  cmd->callback([o] {
    spdlog::set_level(spdlog::level::from_str(common_options().log_level));
    int code = 0;
    try {
      code = serve(*o);
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      code = 2;
    }
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace rise::instructor
