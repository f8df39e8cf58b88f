#pragma once

// The web console's HTTP handlers (cpp-httplib): the token check on every
// request, the built pages, the training reports, and the JSON API —
// /api/world, /api/panel, /api/trainees, /api/reports, /api/stream (SSE),
// the virtual panels' updates, the signed fault buttons, scenario control
// and sim control; and the builder pages' API (instructor/builder_routes.hpp).

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include "instructor/channel_cache.hpp"
#include "instructor/scenario_processes.hpp"
#include "instructor/trainee_links.hpp"
#include "instructor/virtual_panels.hpp"
#include "instructor/web_server.hpp"
#include "msgs/command_auth.hpp"
#include "panels/panel_definition.hpp"
#include "msgs/publisher_session.hpp"

namespace httplib {
class Server;
}
namespace lcm {
class LCM;
}

namespace rise::instructor {

/// What the handlers serve and act on; the WebServer owns all of it and
/// outlives its routes.
struct WebRouteContext {
  const WebServerSettings& settings;
  const std::string& world_text;  ///< /api/world, built once
  const panels::PanelDefinition& console;
  const std::optional<msgs::InstructorKey>& key;  ///< none: fault buttons and scenarios answer 503
  const std::atomic<bool>& running;                  ///< false: the SSE streams end
  lcm::LCM& lcm;
  ChannelCache& cache;
  VirtualPanels& virtual_panels;
  ScenarioProcesses& scenarios;
  const msgs::PublisherWatch& publishers;
  std::atomic<int64_t>& sim_control_seq;  ///< SimControl.seq, counted over every trainee
  const TraineeLinks& links;  ///< live / stale / lost and the clock offset per trainee
};

/// Sets up `http`: its request threads (settings.http_threads, at least 4),
/// the token check, the pages folder and every route. Throws
/// std::runtime_error when the pages folder cannot be served.
void add_routes(httplib::Server& http, const WebRouteContext& context);

}  // namespace rise::instructor
