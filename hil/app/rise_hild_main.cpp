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
#include "msgs/command_auth.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "hil/io/replay_modbus_link.hpp"
#include "hil/panel_state_message.hpp"
#include "hil/session_recorder.hpp"
#include "panels/data_path.hpp"
#include "msgs/publisher_session.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rise-hild: console (CAN, Modbus or HID) → PanelState on LCM, PanelFeedback → console; "
               "--record DIR records a session, `verify` replays one against a golden log"};
  std::string panel_file = "panels/definitions/rise_console.yaml";
  std::vector<std::string> source_urls;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string id = "t1";
  std::string log_level = "info";
  double status_every_s = 0.0;
  double publish_hz = 0.0;
  app.add_option("--panel", panel_file, "panel definition (YAML)")->capture_default_str();
  // --can is the old name, from when every source was a CAN bus.
  app.add_option("--source,--can", source_urls,
                 "transport of each source, one per source in the definition's order: rise-can-v1: "
                 "socketcan://IFACE, socketcand://HOST:PORT/BUS, mem://NAME; rise-modbus-v1 and modbus: "
                 "modbus+tcp://HOST:PORT?unit=N&timeout_ms=T, modbus+rtu:///dev/ttyUSB0?baud=B&parity=E&unit=N, "
                 "replay://FILE.modbus.log?speed=1&loop=0&start=S&stop=S&fast=0 (a recorded trace as the slave); "
                 "hid: hid://VID:PID[?serial=S][&name=TEXT][&interface=N], or - for the definition's device:, "
                 "or replay://FILE.hid?speed=X&loop=N&start=S&stop=S&fast=1 (a hid-recorder file as the device)");
  app.add_option("--lcm", lcm_url, "LCM URL")->capture_default_str();
  app.add_option("--id", id, "trainee/station id used in channel names")->capture_default_str();
  app.add_option("--publish-hz", publish_hz, "PanelState rate (default: the definition's publish_hz, 100)")
      ->check(CLI::Range(1.0, 1000.0));
  app.add_option("--status-every", status_every_s, "log a status line every S seconds (0: on change only)");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")->capture_default_str();
  bool allow_duplicate_id = false;
  app.add_flag("--allow-duplicate-id", allow_duplicate_id,
               "start even when another process already publishes rise/<id>/panel_state (by default that is "
               "refused: two publishers on one station mix their messages)");
  std::string instructor_key_file;
  app.add_option("--instructor-key", instructor_key_file,
                 "instructor key file (hex, mode 0600; default env RISE_INSTRUCTOR_KEY): verifies signed "
                 "FaultCommands on rise/<id>/fault_command; without it every command is rejected")
      ->type_name("FILE");
  double command_window_s = 5.0;
  app.add_option("--command-window", command_window_s, "largest accepted |command time - now| (s)")
      ->capture_default_str();
  std::string record_dir;
  app.add_option("--record", record_dir,
                 "record the session into DIR (created): <source>.log (CAN, candump -l), <source>.modbus.log "
                 "(Modbus transaction trace), <source>.hid (HID, hid-recorder's format), panel_state.lcmlog (every PanelState, lcm-logger's format); "
                 "`rise-hild verify --record-dir DIR` replays it")
      ->type_name("DIR");
  // Inspection commands a lab runs before wiring a console in.
  app.require_subcommand(0, 1);
  std::string dbc_file, log_file;
  CLI::App* dbc = app.add_subcommand("dbc", "CAN database tools");
  CLI::App* dbc_decode = dbc->add_subcommand("decode", "decode a candump log with a DBC, one line per frame");
  dbc->require_subcommand(1);
  dbc_decode->add_option("DBC", dbc_file, "DBC file")->required();
  dbc_decode->add_option("LOG", log_file, "candump -l log")->required();
  std::string hid_file;
  CLI::App* hid = app.add_subcommand("hid", "USB HID tools");
  CLI::App* hid_describe = hid->add_subcommand(
      "describe", "print every field of a HID report descriptor and the named signal it becomes");
  hid->require_subcommand(1);
  hid_describe->add_option("FILE", hid_file,
                           "descriptor: hex dump, C array, hid-recorder R: line, Android CTS register JSON, "
                           "xpadneo markdown, or a binary report_descriptor")
      ->required();
  rise::hil::VerifyOptions verify_options;
  verify_options.panel = panel_file;
  CLI::App* verify = app.add_subcommand(
      "verify", "replay captures as fast as possible and compare the PanelState stream with a golden LCM log; "
                "exit 0 pass, 1 difference (the first is printed with its time and control), 2 bad input");
  verify->add_option("--panel", verify_options.panel, "panel definition (YAML)")->capture_default_str();
  verify->add_option("--capture", verify_options.captures,
                     "capture file, named SOURCE.log (CAN: candump, ASC, TRC), SOURCE.modbus.log (Modbus trace) or "
                     "SOURCE.hid (HID, hid-recorder), or SOURCE=FILE; one per source")
      ->type_name("FILE");
  verify->add_option("--record-dir", verify_options.record_dir,
                     "a `rise-hild --record` directory: its captures, and panel_state.lcmlog as the golden")
      ->type_name("DIR");
  verify->add_option("--golden", verify_options.golden, "golden LCM log (lcm-logger or --record)")->type_name("FILE");
  verify->add_option("--id", verify_options.id, "station id: compare rise/<id>/panel_state (default: the log's one)");
  verify->add_option("--tolerance", verify_options.axis_tolerance, "largest axis difference that matches")
      ->capture_default_str();
  verify->add_option("--time-tolerance-ms", verify_options.time_tolerance_ms,
                     "a message matches the replayed state this far from its utime (frame/publish races)")
      ->capture_default_str();
  if (const auto code = rise::cli::parse_command_line(app, "rise-hild", argc, argv)) return *code;
  spdlog::set_level(spdlog::level::from_str(log_level));
  if (verify->parsed()) return rise::hil::verify_command(verify_options, std::cout, std::cerr);
  if (dbc_decode->parsed()) return rise::hil::dbc_decode(dbc_file, log_file, std::cout, std::cerr);
  if (hid_describe->parsed()) return rise::hil::hid_describe(hid_file, std::cout, std::cerr);
  if (source_urls.empty()) {
    spdlog::error("--source is required (one URL per source of the panel)");
    return 2;
  }

  rise::panels::PanelDefinition definition;
  try {
    definition = rise::panels::load_panel_definition(rise::panels::find_data_file(panel_file));
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  if (publish_hz > 0) definition.publish_hz = publish_hz;
  if (source_urls.size() != definition.sources.size()) {
    spdlog::error("{}: the panel has {} source(s) but {} --source URL(s) were given", definition.file,
                  definition.sources.size(), source_urls.size());
    return 2;
  }
  std::vector<rise::hil::SourceTransport> transports;
  try {
    for (std::size_t i = 0; i < source_urls.size(); ++i) {
      const auto& source = definition.sources[i];
      // A hid source's URL may come from its definition (`device:`): "-".
      if (source.is_hid() && source_urls[i] == "-") source_urls[i] = source.device;
      const bool hid_url = source_urls[i].rfind("hid://", 0) == 0;
      if (source.is_hid() ? !rise::io::is_input_device_url(source_urls[i]) : hid_url)
        throw std::runtime_error("source '" + source.name + "' speaks " + source.protocol + ": '" + source_urls[i] +
                                 "' is " + (source.is_hid() ? "not a hid://VID:PID URL (or - for its device:) "
                                                              "or a replay://FILE.hid"
                                                            : "a HID device URL"));
      if (source.is_hid()) {
        rise::hil::SourceTransport t;
        t.hid = rise::io::open_input_device(source_urls[i]);
        // Without hot-plug the bridge notes it once (Bridge::take_notes).
        if (!hid_url) spdlog::info("source '{}': replaying {}", source.name, source_urls[i]);
        else if (t.hid->hotplug_active()) spdlog::info("source '{}': USB hot-plug through libusb", source.name);
        transports.push_back(std::move(t));
        continue;
      }
      // replay://FILE.modbus.log: a recorded trace answers as the slave did.
      const bool modbus_replay = source.is_modbus() && rise::io::is_replay_url(source_urls[i]);
      const bool modbus_url = rise::io::is_modbus_url(source_urls[i]) || modbus_replay;
      if (modbus_url != source.is_modbus())
        throw std::runtime_error("source '" + source.name + "' speaks " + source.protocol + ": '" + source_urls[i] +
                                 "' is not a " +
                                 (source.is_modbus() ? "modbus+tcp://, modbus+rtu:// or replay://FILE.modbus.log"
                                                     : "CAN") +
                                 " URL");
      rise::hil::SourceTransport t;
      if (modbus_replay) {
        t.modbus = rise::io::open_modbus_link(source_urls[i]);
      } else if (modbus_url) {
        // The definition's unit unless the URL names one.
        auto address = rise::io::parse_modbus_url(source_urls[i]);
        if (source_urls[i].find("unit=") == std::string::npos) address.unit = source.unit;
        t.modbus = rise::io::open_modbus_link(address);
      } else {
        t.can = rise::io::open_can_bus(source_urls[i]);
      }
      transports.push_back(std::move(t));
    }
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  // Wire faults sit right on the transport, under the recorder: a
  // recording holds what the daemon read, so `verify` replays a faulted
  // session as it was.
  std::vector<rise::io::WireFaultSet*> wires(transports.size(), nullptr);
  for (std::size_t i = 0; i < transports.size(); ++i) {
    if (transports[i].can) {
      auto faulty = std::make_unique<rise::io::FaultyCanBus>(std::move(transports[i].can));
      wires[i] = faulty.get();
      transports[i].can = std::move(faulty);
    } else if (transports[i].modbus) {
      auto faulty = std::make_unique<rise::io::FaultyModbusLink>(std::move(transports[i].modbus));
      wires[i] = faulty.get();
      transports[i].modbus = std::move(faulty);
    }
  }
  std::unique_ptr<rise::hil::SessionRecorder> recorder;
  if (!record_dir.empty()) {
    try {
      recorder = std::make_unique<rise::hil::SessionRecorder>(record_dir);
      for (std::size_t i = 0; i < transports.size(); ++i) {
        const auto& source = definition.sources[i];
        const bool url_unit =
            rise::io::is_modbus_url(source_urls[i]) && source_urls[i].find("unit=") != std::string::npos;
        const int unit = url_unit ? rise::io::parse_modbus_url(source_urls[i]).unit : 0;
        if (!recorder->record_source(source.name, transports[i], url_unit ? unit : source.unit))
          spdlog::warn("--record: source '{}' ({}) is not recorded", source.name, source.protocol);
      }
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return 2;
    }
    spdlog::info("recording into {}", record_dir);
  }

  std::optional<rise::msgs::CommandVerifier> verifier;
  if (const std::string key_path = rise::msgs::instructor_key_path(instructor_key_file); !key_path.empty()) {
    try {
      verifier.emplace(rise::msgs::load_instructor_key(key_path), static_cast<int64_t>(command_window_s * 1e6));
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return 2;
    }
    spdlog::info("instructor commands verified with {}", key_path);
  } else {
    spdlog::info("no instructor key: fault commands are rejected");
  }

  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    spdlog::error("cannot open LCM at {}", lcm_url);
    return 2;
  }
  const std::string state_channel = rise::hil::channel(id, "panel_state");
  const std::string feedback_channel = rise::hil::channel(id, "panel_feedback");

  // One publisher per station: listen before the first message.
  const rise_msgs::Publisher self = rise::msgs::init_publisher("rise-hild");
  if (!allow_duplicate_id)
    if (const auto other = rise::msgs::probe_channel<rise_msgs::PanelState>(lcm, state_channel, rise::msgs::kProbeMs)) {
      spdlog::error("{} is already published by {}: refusing to start a second publisher for station '{}' (give "
                    "another --id, or --allow-duplicate-id)",
                    state_channel, rise::msgs::describe(*other, wall_us()), id);
      return 2;
    }

  int64_t seq = 0;
  std::string last_reason = "-";
  rise::hil::TransportFaults transport_faults;
  rise::hil::FaultInjector* injector = nullptr;  // set once the bridge exists
  // A rejected command shows in PanelState for 10 s, beside the faults.
  std::mutex rejected_mutex;
  std::string rejected_note;
  int64_t rejected_until_us = 0;
  // Why a source is down, logged once per change (the reason is also in SourceHealth.down_reason).
  std::vector<std::string> logged_down(definition.sources.size());
  auto log_sources = [&](const rise::hil::PanelSnapshot& snap) {
    for (std::size_t i = 0; i < snap.sources.size() && i < logged_down.size(); ++i) {
      const auto& s = snap.sources[i];
      if (s.connected && !logged_down[i].empty()) {
        spdlog::info("source '{}' up: {}", s.name, source_urls[i]);
        logged_down[i].clear();
      } else if (!s.connected && !s.down_reason.empty() && s.down_reason != logged_down[i]) {
        spdlog::warn("source '{}' down: {}", s.name, s.down_reason);
        logged_down[i] = s.down_reason;
      }
    }
  };
  auto publish = [&](const rise::hil::PanelSnapshot& snap) {
    log_sources(snap);
    auto msg = rise::hil::to_message(definition, snap, id, seq++, wall_us(), source_urls);
    msg.publisher = self;
    if (injector)
      for (auto& f : injector->active(snap.time_us)) msg.active_faults.push_back(std::move(f));
    {
      std::lock_guard lock(rejected_mutex);
      if (snap.time_us < rejected_until_us) msg.active_faults.push_back(rejected_note);
    }
    msg.num_faults = static_cast<int16_t>(msg.active_faults.size());
    // Transport faults act on the wire message: the recording keeps what was sent.
    for (const auto& out : transport_faults.pass(msg, snap.time_us)) {
      lcm.publish(state_channel, &out);
      if (recorder) recorder->record_message(state_channel, out);
    }
    // Log when the reason changes, not every time an age in it grows.
    std::string reason_kind = snap.failsafe_reason;
    std::erase_if(reason_kind, [](char c) { return c >= '0' && c <= '9'; });
    if (reason_kind != last_reason) {
      if (snap.failsafe) spdlog::warn("failsafe: {}", snap.failsafe_reason);
      else spdlog::info("panel ok: all sources healthy");
      last_reason = reason_kind;
    }
  };
  rise::hil::Bridge bridge(definition, std::move(transports), publish);
  rise::hil::FaultInjector fault_injector(bridge, wires, &transport_faults);

  // Signed FaultCommands (panels/command_auth.hpp): verified, then applied
  // to the daemon's layers; sim kinds are rise-sim's and ignored here.
  const std::string fault_channel = rise::hil::channel(id, "fault_command");
  int64_t rejected = 0;
  struct FaultHandler {
    std::function<void(const rise_msgs::FaultCommand&)> on_command;
    void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::FaultCommand* m) { on_command(*m); }
  } fault_handler{[&](const rise_msgs::FaultCommand& c) {
    const int64_t now = rise::hil::monotonic_us();
    std::string why;
    if (!verifier) why = "no instructor key on this station";
    else if (const auto v = verifier->check(c, wall_us()); v != rise::msgs::Verdict::Accepted) why = rise::msgs::to_string(v);
    else if (c.trainee_id != id) why = "meant for trainee '" + c.trainee_id + "'";
    if (!why.empty()) {
      ++rejected;
      spdlog::warn("rejected command on {} from '{}': {} ({} rejected so far)", fault_channel, c.issuer, why, rejected);
      std::lock_guard lock(rejected_mutex);
      rejected_note = "command_rejected: " + why + " from '" + c.issuer + "' (" + std::to_string(rejected) + " rejected)";
      rejected_until_us = now + 10'000'000;
      return;
    }
    if (c.action == "clear") {
      const std::size_t n = fault_injector.clear(c.fault_id, now);
      spdlog::info("fault clear '{}' from '{}': {} cleared", c.fault_id.empty() ? "*" : c.fault_id, c.issuer, n);
      return;
    }
    const auto layer = rise::hil::fault_layer(c.kind);
    if (layer == rise::hil::FaultLayer::Physics || layer == rise::hil::FaultLayer::Sensor) return;  // rise-sim's
    rise::hil::FaultSpec spec{c.fault_id, c.kind, c.target, c.value, c.rate, c.duration_s, static_cast<uint64_t>(c.seed)};
    const std::string error = c.action == "inject" ? fault_injector.inject(spec, now) : "action '" + c.action + "'";
    if (error.empty())
      spdlog::info("fault '{}' from '{}': {} {} value {} rate {} for {} s", c.fault_id, c.issuer, c.kind, c.target,
                   c.value, c.rate, c.duration_s);
    else
      spdlog::warn("fault '{}' from '{}' refused: {}", c.fault_id, c.issuer, error);
  }};
  injector = &fault_injector;
  lcm.subscribe(fault_channel, &FaultHandler::on, &fault_handler)->setQueueCapacity(64);

  struct FeedbackHandler {
    rise::hil::Bridge* bridge;
    void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelFeedback* m) {
      bridge->set_feedback(rise::hil::from_message(*m));
    }
  } handler{&bridge};
  lcm::Subscription* sub = lcm.subscribe(feedback_channel, &FeedbackHandler::on, &handler);
  sub->setQueueCapacity(4);  // only the newest feedback matters

  // Another process publishing on this station's channel: reported once by
  // each side; of two that started together, the later one gives way.
  int exit_code = 0;
  rise::msgs::PublisherListener<rise_msgs::PanelState> others(
      self.session_id, [&](const rise::msgs::PublisherWatch::Other& o) {
        spdlog::warn("another publisher on {}: {}", o.channel, rise::msgs::describe(o.publisher, wall_us()));
        if (allow_duplicate_id || !rise::msgs::gives_way(self, o.publisher, wall_us())) return;
        spdlog::error("{} started first: this rise-hild stops (give another --id, or --allow-duplicate-id)",
                      o.publisher.program);
        exit_code = 2;
        g_stop = 1;
      });
  others.listen(lcm, state_channel);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  bridge.start();
  spdlog::info("rise-hild ready: panel '{}' ({}), publishing {} at {} Hz, feedback from {}",
               definition.name, definition.file, state_channel, definition.publish_hz,
               feedback_channel);

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
      const auto snap = bridge.snapshot();
      for (const auto& s : snap.sources)
        spdlog::info("source {}: connected={} stale={} ok={} bad={} reconnects={} timeouts={} exceptions={} "
                     "error_frames={} bus={}",
                     s.name, s.connected, s.stale, s.frames_ok, s.frames_bad(), s.reconnects, s.timeouts,
                     s.exceptions, s.error_frames, rise::io::to_string(s.bus_state));
      if (recorder) {
        const auto c = recorder->counts();
        spdlog::info("recorder: {} CAN frames, {} Modbus lines, {} HID reports, {} PanelState events, {} failed writes",
                     c.can_frames, c.modbus_lines, c.hid_reports, c.lcm_events, c.write_errors);
      }
    }
  }
  bridge.stop();
  spdlog::info("rise-hild stopped after {} messages", seq);
  if (recorder) {
    const auto c = recorder->counts();
    spdlog::info("recorded {} CAN frames, {} Modbus trace lines, {} HID reports, {} PanelState events into {}",
                 c.can_frames, c.modbus_lines, c.hid_reports, c.lcm_events, recorder->dir());
    if (c.write_errors > 0) spdlog::error("recorder: {} writes failed (disk full?): the recording is incomplete", c.write_errors);
  }
  return exit_code;
}
