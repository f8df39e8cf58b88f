#pragma once

// The instructor's web console: an HTTP server (cpp-httplib) on loopback
// that serves the built pages, a JSON API, and a Server-Sent Events stream of
// the classroom's LCM traffic (rise/<id>/panel_state, robot_state,
// sim_event, task_status, task_event), coalesced to the latest message per
// channel and pushed at push_hz; and the virtual panels whose pages post
// their controls here, published as PanelState under the daemon's safety
// rules (instructor/virtual_panel.hpp). Each trainee's link is watched
// (live, stale, lost) and its clock offset probed, so that the states and
// the signed commands of a station on another host are judged in the right
// clock (instructor/trainee_links.hpp).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "instructor/fault_presets.hpp"  // the console's fault buttons
#include "msgs/channels.hpp"

namespace rise::instructor {

struct WebServerSettings {
  std::string host = "127.0.0.1";   ///< loopback only unless asked otherwise
  int port = 8080;                  ///< 0: any free port (see WebServer::port)
  std::string token;                ///< every request must carry it (non-empty)
  std::string web_dir;              ///< the built pages (instructor/web/dist)
  std::string world_file;           ///< "" → the built-in yard
  std::string robot_file;           ///< the robot file the 3D view takes chassis and cameras from; "" → none
  std::string lcm_url = msgs::kDefaultLcmUrl;
  std::string reports_dir;          ///< "" → no reports
  std::string panel_file;           ///< the console definition the virtual panel copies
  uint32_t virtual_timeout_ms = 200;  ///< a virtual panel without an update for this long fails safe
  double push_hz = 50.0;            ///< SSE push rate (≥ 20)
  /// A trainee not heard for this long shows as lost (instructor/trainee_links.hpp).
  uint32_t lost_after_ms = 500;
  /// How often each trainee's clock offset is probed (msgs/clock_offset.hpp).
  uint32_t clock_probe_ms = 500;
  /// Request threads: every open page holds one for its SSE stream and one
  /// for its keep-alive requests (cpp-httplib's default pool is 8).
  std::size_t http_threads = 64;
  std::string instructor_key_file;  ///< "" → fault buttons answer 503 (msgs/command_auth.hpp)
  std::string issuer = "instructor";  ///< FaultCommand.issuer
  /// Scenario control: the *.yaml scenario files offered (instructor/scenario.hpp)
  /// and the program that runs one (`rise-instructor scenario FILE --trainee ID`,
  /// started per trainee, stopped with SIGTERM, on which it clears its auto_clear faults).
  std::string scenarios_dir;        ///< "" → no scenarios
  std::string scenario_program;     ///< "" → scenario control off
  /// The files the builder pages read and write (/training.html:
  /// instructor/builder_routes.hpp); "" → the builders are off.
  std::string designs_dir;
  /// The world files the Environment Builder edits (instructor/world_builder.hpp); "" → off.
  std::string worlds_dir;
  std::string robots_dir;  ///< the robot files /robot_builder.html edits (instructor/robot_builder_routes.hpp); "" → off
  /// The Console Builder's panel definitions and its live view's source URLs (instructor/console_builder.hpp).
  std::string consoles_dir;
  std::vector<std::string> console_sources;
  /// Told (from the LCM thread) when another process publishes on a channel
  /// where one of this server's virtual panels does; the program logs it.
  std::function<void(const std::string&)> on_duplicate_publisher;
};

class WebServer {
 public:
  /// Loads the world and the panel definition and opens LCM. Throws
  /// std::runtime_error (file:line: key: ... for bad files, or what failed).
  explicit WebServer(WebServerSettings settings);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  /// Binds the socket and starts the threads. Throws std::runtime_error when
  /// it cannot bind: "HOST:PORT: address in use" when another server listens there.
  void start();
  /// Stops the server and the threads; publishes nothing more.
  void stop();
  /// The port bound (after start()).
  int port() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rise::instructor
