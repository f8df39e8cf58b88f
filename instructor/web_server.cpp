#include "instructor/web_server.hpp"

// Eigen before httplib: httplib pulls in <resolv.h>, whose `_res` macro
// breaks Eigen's parameters of that name.
#include "sim/robot_description.hpp"

#include <httplib.h>
#include <json/json.h>
#include <lcm/lcm-cpp.hpp>
#include <poll.h>
#include <sys/socket.h>

#include <atomic>
#include <cerrno>
#include <filesystem>
#include <optional>
#include <regex>
#include <stdexcept>
#include <thread>

#include "hil/io/host_port.hpp"
#include "hil/panel_state_message.hpp"
#include "instructor/channel_cache.hpp"
#include "instructor/scenario_processes.hpp"
#include "instructor/trainee_links.hpp"
#include "instructor/virtual_panels.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_routes.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/clock_offset.hpp"
#include "msgs/command_auth.hpp"
#include "msgs/lcm_decode.hpp"
#include "msgs/publisher_session.hpp"
#include "panels/panel_definition.hpp"
#include "rise_msgs/ClockEcho.hpp"
#include "rise_msgs/ClockProbe.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/SoundCue.hpp"
#include "rise_msgs/TaskEvent.hpp"
#include "rise_msgs/TaskStatus.hpp"
#include "sim/world_description.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;

namespace {

template <class Message>
std::optional<Message> decode(const lcm::ReceiveBuffer* rbuf) {
  Message m;
  if (!msgs::decode_message(rbuf->data, rbuf->data_size, m)) return std::nullopt;
  return m;
}

}  // namespace

// The pieces, each guarding its own state: the channel cache (LCM thread →
// SSE streams), the virtual panels (with their publishing thread), the
// scenario children (with their launcher thread). The LCM thread feeds
// them; the HTTP threads serve them (instructor/web_routes.hpp).
struct WebServer::Impl {
  WebServerSettings settings;
  std::string world_text;
  panels::PanelDefinition console;
  std::optional<msgs::InstructorKey> key;
  lcm::LCM lcm;
  httplib::Server http;
  std::atomic<bool> running{false};
  std::thread http_thread, lcm_thread;
  int bound_port = 0;
  std::atomic<int64_t> sim_control_seq{0};

  // Other processes publishing the trainees' states (this process's own
  // virtual panels come back over LCM too and are not "others").
  msgs::PublisherWatch publishers{msgs::this_publisher().session_id};
  ChannelCache cache;
  std::optional<VirtualPanels> virtual_panels;  // once the console and the key are loaded
  ScenarioProcesses scenarios;
  TraineeLinks links{int64_t{settings.lost_after_ms} * 1000};
  int64_t next_probe_us = 0;  // steady clock
  int64_t probe_seq = 0;

  explicit Impl(WebServerSettings s)
      : settings(std::move(s)),
        lcm(settings.lcm_url),
        scenarios(ScenarioCommand{settings.scenario_program, settings.lcm_url, settings.instructor_key_file,
                                  settings.issuer}) {
    if (settings.token.empty()) throw std::runtime_error("a token is required (--token or --token-file)");
    if (!lcm.good()) throw std::runtime_error("cannot open LCM at " + settings.lcm_url);
    if (!fs::is_regular_file(fs::path(settings.web_dir) / "index.html"))
      throw std::runtime_error(settings.web_dir + ": no index.html (build the pages: npm ci && npm run build in instructor/web)");
    const sim::WorldDescription world =
        settings.world_file.empty() ? sim::default_world() : sim::load_world_description(settings.world_file);
    Json::Value w = world_json(world);
    if (!settings.robot_file.empty()) w["robot"] = robot_json(sim::load_robot_description(settings.robot_file));
    world_text = json_text(w);
    console = panels::load_panel_definition(settings.panel_file);
    if (settings.push_hz < 20.0) throw std::runtime_error("push_hz must be at least 20");
    if (!settings.instructor_key_file.empty()) key = msgs::load_instructor_key(settings.instructor_key_file);
    virtual_panels.emplace(console, settings.virtual_timeout_ms, key, lcm, publishers);
  }

  WebRouteContext route_context() {
    return {settings, world_text, console, key, running, lcm, cache, *virtual_panels, scenarios, publishers,
            sim_control_seq, links};
  }

  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    static const std::regex re("rise/([^/]+)/([a-z_]+)");
    std::smatch m;
    if (!std::regex_match(channel, m, re)) return;
    const std::string trainee = m[1], kind = m[2];
    if (kind == "fault_command") {
      if (auto c = decode<rise_msgs::FaultCommand>(rbuf)) virtual_panels->on_fault_command(trainee, *c);
    } else if (kind == "panel_state") {
      if (auto s = decode<rise_msgs::PanelState>(rbuf)) {
        watch_publisher(channel, trainee, s->publisher);
        heard(trainee, s->publisher, s->utime);
        cache.store_latest(channel, trainee, kind, panel_json(*s));
      }
    } else if (kind == "robot_state") {
      if (auto s = decode<rise_msgs::RobotState>(rbuf)) {
        watch_publisher(channel, trainee, s->publisher);
        heard(trainee, s->publisher, s->utime);
        cache.store_latest(channel, trainee, kind, robot_json(*s));
      }
    } else if (kind == "task_status") {
      if (auto s = decode<rise_msgs::TaskStatus>(rbuf)) {
        watch_publisher(channel, trainee, s->publisher);
        heard(trainee, s->publisher, s->utime);
        cache.store_latest(channel, trainee, kind, task_status_json(*s));
      }
    } else if (kind == "clock_echo") {
      const int64_t t4 = msgs::wall_us();
      auto e = decode<rise_msgs::ClockEcho>(rbuf);
      if (e && e->prober_session == msgs::this_publisher().session_id) links.on_echo(trainee, *e, t4);
    } else if (kind == "panel_feedback") {
      if (auto s = decode<rise_msgs::PanelFeedback>(rbuf)) cache.store_latest(channel, trainee, kind, panel_feedback_json(*s));
    } else if (kind == "sim_event") {
      if (auto s = decode<rise_msgs::SimEvent>(rbuf)) cache.store_event(trainee, kind, sim_event_json(*s));
    } else if (kind == "task_event") {
      if (auto s = decode<rise_msgs::TaskEvent>(rbuf)) cache.store_event(trainee, kind, task_event_json(*s));
    } else if (kind == "sound") {
      if (auto s = decode<rise_msgs::SoundCue>(rbuf)) cache.store_sound(trainee, sound_cue_json(*s));
    }
  }

  // A state from the station's side (not this server's own virtual panel,
  // which says nothing of the station's link and stamps with our clock).
  void heard(const std::string& trainee, const rise_msgs::Publisher& p, int64_t utime) {
    if (p.session_id != msgs::this_publisher().session_id)
      links.heard(trainee, p.host, utime, msgs::wall_us(), msgs::monotonic_us());
  }

  // A second publisher beside one of this server's virtual panels is told
  // to the program (it logs it); /api/trainees lists every duplicate.
  void watch_publisher(const std::string& channel, const std::string& trainee, const rise_msgs::Publisher& p) {
    const auto other = publishers.observe(channel, p, msgs::monotonic_us());
    if (!other || !settings.on_duplicate_publisher) return;
    const bool ours = channel == msgs::panel_state_channel(trainee) && virtual_panels->has(trainee);
    if (ours)
      settings.on_duplicate_publisher("another publisher on " + channel + ": " +
                                      msgs::describe(other->publisher, msgs::wall_us()) +
                                      ", beside this server's virtual panel for '" + trainee + "'");
  }

  void lcm_loop() {
    const int fd = lcm.getFileno();
    while (running) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 50) > 0 && (p.revents & POLLIN)) lcm.handle();
      probe_clocks();
    }
  }

  // Every trainee heard gets a ClockProbe each clock_probe_ms; its station
  // processes echo it (msgs/clock_offset.hpp).
  void probe_clocks() {
    const int64_t now = msgs::monotonic_us();
    if (now < next_probe_us) return;
    next_probe_us = now + int64_t{settings.clock_probe_ms} * 1000;
    for (const std::string& id : links.trainees()) {
      rise_msgs::ClockProbe probe;
      probe.prober_session = msgs::this_publisher().session_id;
      probe.seq = ++probe_seq;
      probe.utime = msgs::wall_us();
      lcm.publish(msgs::clock_probe_channel(id), &probe);
    }
  }

  // cpp-httplib 0.11's default options set SO_REUSEPORT, with which a second
  // server binds the same port and the kernel splits the connections between
  // the two. SO_REUSEADDR only: a restart still gets its port back while old
  // connections sit in TIME_WAIT, and a port in use fails with EADDRINUSE.
  void bind() {
    http.set_socket_options([](socket_t sock) {
      const int on = 1;
      ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    });
    errno = 0;
    if (settings.port == 0) {
      bound_port = http.bind_to_any_port(settings.host);
      if (bound_port < 0) throw std::runtime_error("cannot bind " + settings.host);
      return;
    }
    const std::string address = hil::io::format_host_port(settings.host, static_cast<uint16_t>(settings.port));
    if (!http.bind_to_port(settings.host, settings.port)) {
      // cpp-httplib closes the socket after the failed bind() or listen(), which keeps errno.
      if (errno == EADDRINUSE) throw std::runtime_error(address + ": address in use");
      throw std::runtime_error("cannot bind " + address);
    }
    bound_port = settings.port;
  }
};

WebServer::WebServer(WebServerSettings settings) : impl_(std::make_unique<Impl>(std::move(settings))) {}

WebServer::~WebServer() { stop(); }

void WebServer::start() {
  Impl& d = *impl_;
  add_routes(d.http, d.route_context());
  d.lcm.subscribeFunction("rise/.*/(panel_state|robot_state|sim_event|task_status|task_event|sound|fault_command|clock_echo|panel_feedback)",
                          +[](const lcm::ReceiveBuffer* rbuf, const std::string& channel, Impl* self) {
                            self->on_message(rbuf, channel);
                          },
                          &d);
  d.bind();
  d.running = true;
  d.lcm_thread = std::thread([&d] { d.lcm_loop(); });
  d.virtual_panels->start();
  d.http_thread = std::thread([&d] { d.http.listen_after_bind(); });
}

void WebServer::stop() {
  Impl& d = *impl_;
  if (!d.running.exchange(false)) return;
  d.cache.close();
  d.http.stop();
  for (auto* t : {&d.http_thread, &d.lcm_thread})
    if (t->joinable()) t->join();
  d.scenarios.stop_all();
  d.virtual_panels->stop();
}

int WebServer::port() const { return impl_->bound_port; }

}  // namespace rise::instructor
