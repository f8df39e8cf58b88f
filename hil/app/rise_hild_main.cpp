// rise-hild: the HIL daemon. Reads the console's frames from its sources,
// maps them to named controls under the safety rules, publishes PanelState on
// LCM and sends PanelFeedback back to the console.

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <csignal>
#include <chrono>
#include <functional>
#include <iostream>
#include <mutex>
#include <optional>
#include <poll.h>

#include "cli/command_line.hpp"
#include "hil/app/inspect_commands.hpp"
#include "hil/app/verify_command.hpp"
#include "hil/bridge.hpp"
#include "hil/fault_injector.hpp"
#include "hil/panel_state_message.hpp"
#include "hil/session_recorder.hpp"
#include "hil/source_factory.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/clock_offset.hpp"
#include "msgs/command_auth.hpp"
#include "msgs/lcm_decode.hpp"
#include "msgs/publisher_session.hpp"
#include "panels/data_path.hpp"
#include "rise_msgs/FaultCommand.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

// The daemon's command line.
struct DaemonOptions {
  std::string panel_file = "panels/definitions/rise_console.yaml";
  std::vector<std::string> source_urls;
  std::string lcm_url = rise::msgs::kDefaultLcmUrl;
  std::string id = "t1";
  std::string log_level = "info";
  double status_every_s = 0.0;
  double publish_hz = 0.0;
  bool allow_duplicate_id = false;
  std::string instructor_key_file;
  double command_window_s = 5.0;
  std::string record_dir;
};

void add_daemon_options(CLI::App& app, DaemonOptions& o) {
  app.add_option("--panel", o.panel_file, "panel definition (YAML)")->capture_default_str();
  // --can is the old name, from when every source was a CAN bus.
  app.add_option("--source,--can", o.source_urls,
                 "transport of each source, one per source in the definition's order: rise-can-v1, dbc, "
                 "canopen and j1939: socketcan://IFACE, slcan:///dev/ttyACM0, socketcand://HOST:PORT/BUS, "
                 "replay://FILE (candump/ASC/TRC/BLF/pcap), mem://NAME; rise-modbus-v1 and modbus: "
                 "modbus+tcp://HOST:PORT?unit=N&timeout_ms=T, modbus+rtu:///dev/ttyUSB0?baud=B&parity=E&unit=N, "
                 "replay://FILE.modbus.log?speed=1&loop=0&start=S&stop=S&fast=0 (a recorded trace as the slave); "
                 "hid: hid://VID:PID[?serial=S][&name=TEXT][&interface=N], or - for the definition's device:, "
                 "or replay://FILE.hid?speed=X&loop=N&start=S&stop=S&fast=1 (a hid-recorder file as the device), "
                 "or evdev:///dev/input/eventN, evdev://by-id/NAME, evdev://name/DEVICE%20NAME, evdev://VID:PID");
  app.add_option("--lcm", o.lcm_url, "LCM URL")->capture_default_str();
  app.add_option("--id", o.id, "trainee/station id used in channel names")->capture_default_str();
  app.add_option("--publish-hz", o.publish_hz, "PanelState rate (default: the definition's publish_hz, 100)")
      ->check(CLI::Range(1.0, 1000.0));
  app.add_option("--status-every", o.status_every_s, "log a status line every S seconds (0: on change only)");
  app.add_option("--log-level", o.log_level, "trace, debug, info, warn, error")->capture_default_str();
  app.add_flag("--allow-duplicate-id", o.allow_duplicate_id,
               "start even when another process already publishes rise/<id>/panel_state (by default that is "
               "refused: two publishers on one station mix their messages)");
  app.add_option("--instructor-key", o.instructor_key_file,
                 "instructor key file (hex, mode 0600; default env RISE_INSTRUCTOR_KEY): verifies signed "
                 "FaultCommands on rise/<id>/fault_command; without it every command is rejected")
      ->type_name("FILE");
  app.add_option("--command-window", o.command_window_s, "largest accepted |command time - now| (s)")
      ->capture_default_str();
  app.add_option("--record", o.record_dir,
                 "record the session into DIR (created): <source>.log (CAN, candump -l), <source>.modbus.log "
                 "(Modbus transaction trace), <source>.hid (HID, hid-recorder's format), panel_state.lcmlog (every PanelState, lcm-logger's format); "
                 "`rise-hild verify --record-dir DIR` replays it")
      ->type_name("DIR");
}

// Inspection commands a lab runs before wiring a console in, and verify.
struct Subcommands {
  CLI::App* dbc_decode = nullptr;
  CLI::App* modbus_decode = nullptr;
  CLI::App* hid_describe = nullptr;
  CLI::App* verify = nullptr;
  std::string dbc_file, log_file, hid_file, modbus_capture;
  rise::hil::VerifyOptions verify_options;
};

void add_subcommands(CLI::App& app, Subcommands& s, const std::string& panel_file) {
  app.require_subcommand(0, 1);
  CLI::App* dbc = app.add_subcommand("dbc", "CAN database tools");
  s.dbc_decode = dbc->add_subcommand("decode", "decode a CAN log with a DBC, one line per frame");
  dbc->require_subcommand(1);
  s.dbc_decode->add_option("DBC", s.dbc_file, "DBC file")->required();
  s.dbc_decode->add_option("LOG", s.log_file, "CAN log: candump -l, Vector ASC or BLF, PEAK TRC, pcap/pcapng of SocketCAN")->required();
  CLI::App* modbus = app.add_subcommand("modbus", "Modbus tools");
  s.modbus_decode = modbus->add_subcommand(
      "decode", "print the Modbus/TCP transactions of a pcap/pcapng capture as a table, with response times");
  modbus->require_subcommand(1);
  s.modbus_decode->add_option("CAPTURE", s.modbus_capture, "pcap or pcapng (tcpdump, Wireshark) of TCP port 502")
      ->required();
  CLI::App* hid = app.add_subcommand("hid", "USB HID tools");
  s.hid_describe = hid->add_subcommand(
      "describe", "print every field of a HID report descriptor and the named signal it becomes");
  hid->require_subcommand(1);
  s.hid_describe->add_option("FILE", s.hid_file,
                             "descriptor: hex dump, C array, hid-recorder R: line, Android CTS register JSON, "
                             "xpadneo markdown, or a binary report_descriptor")
      ->required();
  rise::hil::VerifyOptions& v = s.verify_options;
  v.panel = panel_file;
  s.verify = app.add_subcommand(
      "verify", "replay captures as fast as possible and compare the PanelState stream with a golden LCM log; "
                "exit 0 pass, 1 difference (the first is printed with its time and control), 2 bad input");
  s.verify->add_option("--panel", v.panel, "panel definition (YAML)")->capture_default_str();
  s.verify->add_option("--capture", v.captures,
                       "capture file, named SOURCE.log (CAN: candump, ASC, TRC, BLF, pcap/pcapng), SOURCE.modbus.log (Modbus trace) or "
                       "SOURCE.hid (HID, hid-recorder), or SOURCE=FILE; one per source")
      ->type_name("FILE");
  s.verify->add_option("--record-dir", v.record_dir,
                       "a `rise-hild --record` directory: its captures, and panel_state.lcmlog as the golden")
      ->type_name("DIR");
  s.verify->add_option("--golden", v.golden, "golden LCM log (lcm-logger or --record)")->type_name("FILE");
  s.verify->add_option("--id", v.id, "station id: compare rise/<id>/panel_state (default: the log's one)");
  s.verify->add_option("--tolerance", v.axis_tolerance, "largest axis difference that matches")
      ->capture_default_str();
  s.verify->add_option("--time-tolerance-ms", v.time_tolerance_ms,
                       "a message matches the replayed state this far from its utime (frame/publish races)")
      ->capture_default_str();
}

// The exit code of the subcommand given, if one was.
std::optional<int> run_subcommand(const Subcommands& s) {
  if (s.verify->parsed()) return rise::hil::verify_command(s.verify_options, std::cout, std::cerr);
  if (s.dbc_decode->parsed()) return rise::hil::dbc_decode(s.dbc_file, s.log_file, std::cout, std::cerr);
  if (s.modbus_decode->parsed()) return rise::hil::modbus_decode(s.modbus_capture, std::cout, std::cerr);
  if (s.hid_describe->parsed()) return rise::hil::hid_describe(s.hid_file, std::cout, std::cerr);
  return std::nullopt;
}

// The panel and its sources' transports, or nullopt (logged) when either
// cannot be had.
struct Panel {
  rise::panels::PanelDefinition definition;
  rise::hil::PanelSources sources;
};
std::optional<Panel> open_panel(const DaemonOptions& o) {
  Panel panel;
  try {
    panel.definition = rise::panels::load_panel_definition(rise::panels::find_data_file(o.panel_file));
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return std::nullopt;
  }
  if (o.publish_hz > 0) panel.definition.publish_hz = o.publish_hz;
  try {
    panel.sources = rise::hil::open_panel_sources(panel.definition, o.source_urls, o.record_dir);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return std::nullopt;
  }
  for (const std::string& note : panel.sources.notes) spdlog::info("{}", note);
  if (panel.sources.recorder) spdlog::info("recording into {}", o.record_dir);
  return panel;
}

// The instructor's key verifies fault commands; false (logged) when the key
// given cannot be read.
bool load_verifier(const DaemonOptions& o, std::optional<rise::msgs::CommandVerifier>& verifier) {
  const std::string key_path = rise::msgs::instructor_key_path(o.instructor_key_file);
  if (key_path.empty()) {
    spdlog::info("no instructor key: fault commands are rejected");
    return true;
  }
  try {
    verifier.emplace(rise::msgs::load_instructor_key(key_path), static_cast<int64_t>(o.command_window_s * 1e6));
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return false;
  }
  spdlog::info("instructor commands verified with {}", key_path);
  return true;
}

// Publishes each snapshot as PanelState on the station's channel, with the
// faults in effect and a rejected command beside it, through the transport
// faults and into the recording; logs a source going down or up and the
// failsafe reason when it changes.
class StatePublisher {
 public:
  StatePublisher(lcm::LCM& lcm, const DaemonOptions& o, const Panel& panel, const rise_msgs::Publisher& self)
      : lcm_(lcm),
        id_(o.id),
        channel_(rise::msgs::panel_state_channel(o.id)),
        panel_(panel),
        self_(self),
        logged_down_(panel.definition.sources.size()) {}

  void publish(const rise::hil::PanelSnapshot& snap) {
    log_sources(snap);
    auto msg = rise::hil::to_message(panel_.definition, snap, id_, seq_++, rise::msgs::wall_us(), panel_.sources.urls);
    msg.publisher = self_;
    if (injector_)
      for (auto& f : injector_->active(snap.time_us)) msg.active_faults.push_back(std::move(f));
    {
      std::lock_guard lock(rejected_mutex_);
      if (snap.time_us < rejected_until_us_) msg.active_faults.push_back(rejected_note_);
    }
    msg.num_faults = static_cast<int16_t>(msg.active_faults.size());
    // Transport faults act on the wire message: the recording keeps what was sent.
    for (const auto& out : transport_faults_.pass(msg, snap.time_us)) {
      lcm_.publish(channel_, &out);
      if (panel_.sources.recorder) panel_.sources.recorder->record_message(channel_, out);
    }
    log_reason(snap);
  }
  /// A rejected command shows in PanelState until until_us, beside the faults.
  void show_rejected(std::string note, int64_t until_us) {
    std::lock_guard lock(rejected_mutex_);
    rejected_note_ = std::move(note);
    rejected_until_us_ = until_us;
  }
  void set_injector(rise::hil::FaultInjector* injector) { injector_ = injector; }
  rise::hil::TransportFaults& transport_faults() { return transport_faults_; }
  const std::string& channel() const { return channel_; }
  int64_t messages() const { return seq_; }

 private:
  // Why a source is down, logged once per change (the reason is also in SourceHealth.down_reason).
  void log_sources(const rise::hil::PanelSnapshot& snap) {
    for (std::size_t i = 0; i < snap.sources.size() && i < logged_down_.size(); ++i) {
      const auto& s = snap.sources[i];
      if (s.connected && !logged_down_[i].empty()) {
        spdlog::info("source '{}' up: {}", s.name, panel_.sources.urls[i]);
        logged_down_[i].clear();
      } else if (!s.connected && !s.down_reason.empty() && s.down_reason != logged_down_[i]) {
        spdlog::warn("source '{}' down: {}", s.name, s.down_reason);
        logged_down_[i] = s.down_reason;
      }
    }
  }
  // Logged when the reason changes, not every time an age in it grows.
  void log_reason(const rise::hil::PanelSnapshot& snap) {
    std::string reason_kind = snap.failsafe_reason;
    std::erase_if(reason_kind, [](char c) { return c >= '0' && c <= '9'; });
    if (reason_kind == last_reason_) return;
    if (snap.failsafe) spdlog::warn("failsafe: {}", snap.failsafe_reason);
    else spdlog::info("panel ok: all sources healthy");
    last_reason_ = reason_kind;
  }

  lcm::LCM& lcm_;
  std::string id_;
  std::string channel_;
  const Panel& panel_;
  const rise_msgs::Publisher& self_;
  int64_t seq_ = 0;
  std::string last_reason_ = "-";
  std::vector<std::string> logged_down_;
  rise::hil::TransportFaults transport_faults_;
  rise::hil::FaultInjector* injector_ = nullptr;  // set once the bridge exists
  std::mutex rejected_mutex_;
  std::string rejected_note_;
  int64_t rejected_until_us_ = 0;
};

// Signed FaultCommands (msgs/command_auth.hpp): verified, then applied
// to the daemon's layers; sim kinds are rise-sim's and ignored here.
class FaultCommands {
 public:
  FaultCommands(const DaemonOptions& o, std::optional<rise::msgs::CommandVerifier>& verifier,
                rise::hil::FaultInjector& injector, StatePublisher& publisher)
      : id_(o.id), channel_(rise::msgs::fault_command_channel(o.id)), verifier_(verifier),
        injector_(injector), publisher_(publisher) {}

  void listen(lcm::LCM& lcm) { rise::msgs::subscribe<&FaultCommands::on>(lcm, channel_, this)->setQueueCapacity(64); }

 private:
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::FaultCommand* m) {
    const rise_msgs::FaultCommand& c = *m;
    const int64_t now = rise::msgs::monotonic_us();
    if (const std::string why = refusal(c); !why.empty()) {
      ++rejected_;
      spdlog::warn("rejected command on {} from '{}': {} ({} rejected so far)", channel_, c.issuer, why, rejected_);
      publisher_.show_rejected(
          "command_rejected: " + why + " from '" + c.issuer + "' (" + std::to_string(rejected_) + " rejected)",
          now + 10'000'000);
      return;
    }
    if (c.action == "clear") {
      const std::size_t n = injector_.clear(c.fault_id, now);
      spdlog::info("fault clear '{}' from '{}': {} cleared", c.fault_id.empty() ? "*" : c.fault_id, c.issuer, n);
      return;
    }
    const auto layer = rise::hil::fault_layer(c.kind);
    if (layer == rise::hil::FaultLayer::Physics || layer == rise::hil::FaultLayer::Sensor) return;  // rise-sim's
    rise::hil::FaultSpec spec{c.fault_id, c.kind, c.target, c.value, c.rate, c.duration_s, static_cast<uint64_t>(c.seed)};
    const std::string error = c.action == "inject" ? injector_.inject(spec, now) : "action '" + c.action + "'";
    if (error.empty())
      spdlog::info("fault '{}' from '{}': {} {} value {} rate {} for {} s", c.fault_id, c.issuer, c.kind, c.target,
                   c.value, c.rate, c.duration_s);
    else
      spdlog::warn("fault '{}' from '{}' refused: {}", c.fault_id, c.issuer, error);
  }
  // Why a command is rejected; empty when it is accepted.
  std::string refusal(const rise_msgs::FaultCommand& c) {
    if (!verifier_) return "no instructor key on this station";
    if (const auto v = verifier_->check(c, rise::msgs::wall_us()); v != rise::msgs::Verdict::Accepted)
      return rise::msgs::to_string(v);
    if (c.trainee_id != id_) return "meant for trainee '" + c.trainee_id + "'";
    return {};
  }

  std::string id_;
  std::string channel_;
  std::optional<rise::msgs::CommandVerifier>& verifier_;
  rise::hil::FaultInjector& injector_;
  StatePublisher& publisher_;
  int64_t rejected_ = 0;
};

struct FeedbackHandler {
  rise::hil::Bridge* bridge;
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelFeedback* m) {
    bridge->set_feedback(rise::hil::from_message(*m));
  }
};

void log_status(const rise::hil::PanelSnapshot& snap, const rise::hil::SessionRecorder* recorder) {
  for (const auto& s : snap.sources)
    spdlog::info("source {}: connected={} stale={} ok={} bad={} reconnects={} timeouts={} exceptions={} "
                 "error_frames={} bus={}",
                 s.name, s.connected, s.stale, s.frames_ok, s.frames_bad(), s.reconnects, s.timeouts,
                 s.exceptions, s.error_frames, rise::hil::io::to_string(s.bus_state));
  if (recorder) {
    const auto c = recorder->counts();
    spdlog::info("recorder: {} CAN frames, {} Modbus lines, {} HID reports, {} PanelState events, {} failed writes",
                 c.can_frames, c.modbus_lines, c.hid_reports, c.lcm_events, c.write_errors);
  }
}

// Handles LCM and logs the bridge's notes, a failing recorder and, every
// status_every_s, a status line, until SIGINT or SIGTERM.
void run_until_stopped(lcm::LCM& lcm, rise::hil::Bridge& bridge, const rise::hil::SessionRecorder* recorder,
                       double status_every_s) {
  auto next_status = std::chrono::steady_clock::now();
  int64_t write_errors_reported = 0;
  while (!g_stop) {
    pollfd pfd{lcm.getFileno(), POLLIN, 0};
    if (::poll(&pfd, 1, 50) > 0) lcm.handle();
    for (const std::string& note : bridge.take_notes()) spdlog::warn("{}", note);

    // A full disk costs records, not the session: said once, then at each status line.
    if (recorder && write_errors_reported == 0 && recorder->counts().write_errors > 0) {
      write_errors_reported = recorder->counts().write_errors;
      spdlog::error("recorder: writes into {} fail (disk full?): records are being lost", recorder->dir());
    }
    if (status_every_s > 0 && std::chrono::steady_clock::now() >= next_status) {
      next_status += std::chrono::microseconds(static_cast<int64_t>(status_every_s * 1e6));
      log_status(bridge.snapshot(), recorder);
    }
  }
}

void log_stopped(int64_t messages, const rise::hil::SessionRecorder* recorder) {
  spdlog::info("rise-hild stopped after {} messages, {} malformed LCM messages dropped", messages,
               rise::msgs::malformed_messages().load());
  if (!recorder) return;
  const auto c = recorder->counts();
  spdlog::info("recorded {} CAN frames, {} Modbus trace lines, {} HID reports, {} PanelState events into {}",
               c.can_frames, c.modbus_lines, c.hid_reports, c.lcm_events, recorder->dir());
  if (c.write_errors > 0) spdlog::error("recorder: {} writes failed (disk full?): the recording is incomplete", c.write_errors);
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rise-hild: console (CAN, Modbus or HID) → PanelState on LCM, PanelFeedback → console; "
               "--record DIR records a session, `verify` replays one against a golden log"};
  DaemonOptions o;
  add_daemon_options(app, o);
  Subcommands subcommands;
  add_subcommands(app, subcommands, o.panel_file);
  if (const auto code = rise::cli::parse_command_line(app, "rise-hild", argc, argv)) return *code;
  spdlog::set_level(spdlog::level::from_str(o.log_level));
  if (const auto code = run_subcommand(subcommands)) return *code;
  if (o.source_urls.empty()) {
    spdlog::error("--source is required (one URL per source of the panel)");
    return 2;
  }
  std::optional<Panel> panel = open_panel(o);
  std::optional<rise::msgs::CommandVerifier> verifier;
  if (!panel || !load_verifier(o, verifier)) return 2;

  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    spdlog::error("cannot open LCM at {}", o.lcm_url);
    return 2;
  }
  // One publisher per station: listen before the first message.
  const rise_msgs::Publisher self = rise::msgs::init_publisher("rise-hild");
  StatePublisher publisher(lcm, o, *panel, self);
  if (!o.allow_duplicate_id)
    if (const auto other = rise::msgs::probe_channel<rise_msgs::PanelState>(lcm, publisher.channel(), rise::msgs::kProbeMs)) {
      spdlog::error("{} is already published by {}: refusing to start a second publisher for station '{}' (give "
                    "another --id, or --allow-duplicate-id)",
                    publisher.channel(), rise::msgs::describe(*other, rise::msgs::wall_us()), o.id);
      return 2;
    }

  rise::hil::Bridge bridge(panel->definition, std::move(panel->sources.transports),
                           [&](const rise::hil::PanelSnapshot& snap) { publisher.publish(snap); });
  rise::hil::FaultInjector fault_injector(bridge, panel->sources.wires, &publisher.transport_faults());
  FaultCommands fault_commands(o, verifier, fault_injector, publisher);
  publisher.set_injector(&fault_injector);
  fault_commands.listen(lcm);
  rise::msgs::ClockEchoResponder clock_echo(lcm, self);  // the instructor measures this host's clock offset
  clock_echo.listen(o.id);

  const std::string feedback_channel = rise::msgs::panel_feedback_channel(o.id);
  FeedbackHandler handler{&bridge};
  lcm::Subscription* sub = rise::msgs::subscribe<&FeedbackHandler::on>(lcm, feedback_channel, &handler);
  sub->setQueueCapacity(4);  // only the newest feedback matters

  // Another process publishing on this station's channel: reported once by
  // each side; of two that started together, the later one gives way.
  int exit_code = 0;
  rise::msgs::PublisherListener<rise_msgs::PanelState> others(
      self.session_id, [&](const rise::msgs::PublisherWatch::Other& other) {
        spdlog::warn("another publisher on {}: {}", other.channel, rise::msgs::describe(other.publisher, rise::msgs::wall_us()));
        if (o.allow_duplicate_id || !rise::msgs::gives_way(self, other.publisher, rise::msgs::wall_us())) return;
        spdlog::error("{} started first: this rise-hild stops (give another --id, or --allow-duplicate-id)",
                      other.publisher.program);
        exit_code = 2;
        g_stop = 1;
      });
  others.listen(lcm, publisher.channel());

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  bridge.start();
  spdlog::info("rise-hild ready: panel '{}' ({}), publishing {} at {} Hz, feedback from {}",
               panel->definition.name, panel->definition.file, publisher.channel(), panel->definition.publish_hz,
               feedback_channel);
  run_until_stopped(lcm, bridge, panel->sources.recorder.get(), o.status_every_s);
  bridge.stop();
  log_stopped(publisher.messages(), panel->sources.recorder.get());
  return exit_code;
}
