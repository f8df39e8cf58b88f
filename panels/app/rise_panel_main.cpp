// rise-panel: the console's firmware emulated on a real transport (CAN,
// Modbus, or a HID device through uhid), played from a scripted timeline.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <csignal>
#include <thread>

#include "cli/command_line.hpp"
#include "firmware_protocol/hid_text.hpp"
#include "hil/io/can_bus.hpp"
#include "hil/io/hid_device.hpp"
#include "hil/io/modbus_server.hpp"
#include "hil/io/uhid_device.hpp"
#include "msgs/clock.hpp"
#include "panels/app/replay_command.hpp"
#include "panels/canopen_emulator.hpp"
#include "panels/console_emulator.hpp"
#include "panels/data_path.hpp"
#include "panels/hid_emulator.hpp"
#include "panels/j1939_emulator.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct EmulateOptions {
  std::string panel = "panels/definitions/rise_console.yaml";
  std::string source;
  std::string can_url = "socketcand+listen://127.0.0.1:29536/can0";
  std::string modbus_url;  ///< set: serve rise-modbus-v1 instead of CAN
  std::string hid_file;    ///< set: be a HID device (uhid) described by this report descriptor
  std::string hid_id;      ///< VID:PID (hex); default: the descriptor file's, else the source's device URL
  std::string hid_name;    ///< product string; default: the descriptor file's name
  double hid_period_ms = 8.0;
  int j1939_address = 254;  ///< j1939 source: where the console claims (254: the definition's)
  std::string script;
  bool loop = false;
  bool hold = false;
  bool start_on_feedback = false;
};

// The scripted person: plays the timeline against the wall clock, from the
// moment start() is called (at once, or when the host is there).
class ScriptClock {
 public:
  ScriptClock(const rise::panels::Timeline& timeline, const EmulateOptions& o) : timeline_(timeline), o_(o) {}

  void start(int64_t now_us) { start_us_ = now_us; }
  /// Applies the events due at now_us; false once the script is over. A
  /// looped script restarts the emulator (`restart()`: every directive's
  /// state undone) before its first event plays again.
  template <typename Emulator>
  bool step(int64_t now_us, const rise::panels::PanelDefinition& definition, Emulator& emulator) {
    const double t = static_cast<double>(now_us - start_us_) * 1e-6;
    const auto& events = timeline_.events;
    while (next_ < events.size() && events[next_].time_s <= t) {
      const auto& e = events[next_++];
      emulator.apply(e);
      if (e.kind == rise::panels::TimelineEvent::Kind::Set)
        spdlog::debug("t={:.2f} {} set", t, definition.controls[e.control].name);
      else
        spdlog::info("t={:.2f} {}:{} directive", t, timeline_.file, e.line);
    }
    if (events.empty() || next_ < events.size()) return true;
    // The last event holds for kTailS (a final @silent is a source loss the
    // host must see), then a looped script starts again.
    if (o_.loop && t > timeline_.end_time_s() + kTailS) {
      start_us_ = now_us;
      next_ = 0;
      emulator.restart();
      spdlog::info("{}: script restarts", timeline_.file);
      return true;
    }
    return o_.loop || o_.hold || t <= timeline_.end_time_s() + kTailS;
  }

  static constexpr double kTailS = 0.5;

 private:
  const rise::panels::Timeline& timeline_;
  const EmulateOptions& o_;
  int64_t start_us_ = 0;
  std::size_t next_ = 0;
};

// HID mode: a uhid device that the host's HID stack sees as plugged in.
int run_emulate_hid(const EmulateOptions& o, const rise::panels::PanelDefinition& definition, std::size_t source,
                    const rise::panels::Timeline& timeline) {
  using namespace rise;
  namespace fp = rise::firmware_protocol;
  hil::io::UhidSettings settings;
  std::unique_ptr<panels::HidEmulator> emulator;
  try {
    const fp::HidDescriptorSource file = fp::read_hid_descriptor_file(o.hid_file);
    const fp::HidParseResult parsed = fp::parse_hid_descriptor(file.bytes);
    if (!parsed)
      throw std::runtime_error(o.hid_file + ": " + std::string(fp::to_string(parsed.error)) + " at byte " +
                               std::to_string(parsed.error_offset));
    std::string id = o.hid_id;
    if (id.empty() && (file.vendor_id != 0 || file.product_id != 0))
      id = fmt::format("{:04x}:{:04x}", file.vendor_id, file.product_id);
    std::string url = id.empty() ? definition.sources[source].device : "hid://" + id;
    if (url.empty())
      throw std::runtime_error(o.hid_file + " gives no VID:PID and source '" + definition.sources[source].name +
                               "' no device: give --hid-id VID:PID");
    std::string error;
    const auto parsed_url = hil::io::parse_hid_url(url, &error);
    if (!parsed_url) throw std::runtime_error("--hid-id: " + error);
    settings.vendor_id = parsed_url->vendor_id;
    settings.product_id = parsed_url->product_id;
    settings.uniq = parsed_url->serial;
    settings.name = !o.hid_name.empty() ? o.hid_name
                    : !file.name.empty() ? file.name
                                         : "rise-panel " + definition.name + " " + definition.sources[source].name;
    settings.descriptor = file.bytes;
    panels::HidEmulatorSettings emulator_settings;
    emulator_settings.report_period_us = static_cast<int64_t>(o.hid_period_ms * 1000.0);
    emulator = std::make_unique<panels::HidEmulator>(definition, source, parsed.descriptor, emulator_settings);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  std::unique_ptr<hil::io::UhidDevice> device;
  try {
    device = std::make_unique<hil::io::UhidDevice>(settings);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  if (device->create() != hil::io::IoStatus::Ok) {
    spdlog::error("{}", device->last_error());
    return 2;
  }
  spdlog::info("rise-panel ready: emulating '{}' source '{}' as HID device {:04x}:{:04x} '{}' on /dev/uhid",
               definition.name, definition.sources[source].name, settings.vendor_id, settings.product_id,
               settings.name);

  ScriptClock script(timeline, o);
  bool started = !o.start_on_feedback;
  script.start(rise::msgs::monotonic_us());
  hil::io::UhidEvent event;
  while (!g_stop) {
    const int64_t now = rise::msgs::monotonic_us();
    // The scripted person starts once the host has opened the device.
    if (!started) {
      script.start(now);
      if (device->is_open_by_host()) {
        started = true;
        spdlog::info("host opened the device: script starts");
      }
    }
    if (!script.step(now, definition, *emulator)) break;
    if (emulator->ended()) break;
    emulator->tick(*device, now);
    // Host events until the next millisecond tick.
    hil::io::IoStatus st;
    while ((st = device->poll(event, 1)) == hil::io::IoStatus::Ok) {
      if (event.kind == hil::io::UhidEvent::Kind::Output && emulator->on_output(event.data))
        spdlog::info("feedback: {}", emulator->feedback_text());
      if (event.kind == hil::io::UhidEvent::Kind::Start) spdlog::info("the kernel bound the device");
    }
    if (st == hil::io::IoStatus::Disconnected) {
      spdlog::error("{}", device->last_error());
      return 1;
    }
  }
  device->destroy();
  spdlog::info("rise-panel stopped: {} reports sent, {} output reports received ({} bad)", emulator->reports_sent(),
               emulator->outputs_received(), emulator->bad_outputs());
  return 0;
}

// CANopen: the node of a protocol canopen source on the CAN transport; the
// script starts (with --start-on-feedback) once the master started the node.
int run_emulate_canopen(const EmulateOptions& o, const rise::panels::PanelDefinition& definition, std::size_t source,
                        const rise::panels::Timeline& timeline, rise::hil::io::CanBus& bus) {
  using namespace rise;
  using firmware_protocol::canopen::NmtState;
  panels::CanopenEmulator emulator(definition, source);
  spdlog::info("rise-panel ready: emulating '{}' source '{}' as CANopen node {} on {}", definition.name,
               definition.sources[source].name, definition.sources[source].node, o.can_url);
  ScriptClock script(timeline, o);
  script.start(msgs::monotonic_us());
  bool started = !o.start_on_feedback;
  NmtState shown = emulator.state();
  hil::io::CanFrame frame;
  while (!g_stop) {
    const int64_t now = msgs::monotonic_us();
    if (!started) {
      script.start(now);
      if (emulator.state() == NmtState::Operational) {
        started = true;
        spdlog::info("node started by the master: script starts");
      }
    }
    if (!script.step(now, definition, emulator) || emulator.ended()) break;
    if (bus.is_open()) emulator.tick(bus, now);
    else bus.reopen();
    while (bus.is_open() && bus.receive(frame, 1) == hil::io::IoStatus::Ok)
      if (emulator.on_frame(bus, frame, msgs::monotonic_us())) spdlog::info("feedback: {}", emulator.feedback_text());
    if (emulator.state() != shown) {
      shown = emulator.state();
      spdlog::info("NMT state: {}", firmware_protocol::canopen::to_string(shown));
    }
    if (!bus.is_open()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  spdlog::info("rise-panel stopped: {} frames sent, {} SYNC seen", emulator.frames_sent(), emulator.syncs_seen());
  return 0;
}

// A j1939 source: the console's J1939 firmware (panels/j1939_emulator.hpp)
// on a CAN bus, its address claimed before it sends.
int run_emulate_j1939(const EmulateOptions& o, const rise::panels::PanelDefinition& definition, std::size_t source,
                      const rise::panels::Timeline& timeline, rise::hil::io::CanBus& bus) {
  using namespace rise;
  panels::J1939EmulatorSettings settings;
  settings.address = static_cast<uint8_t>(o.j1939_address);
  panels::J1939Emulator emulator(definition, source, settings);
  spdlog::info("rise-panel ready: emulating '{}' source '{}' as a J1939 console on {}", definition.name,
               definition.sources[source].name, o.can_url);
  ScriptClock script(timeline, o);
  script.start(rise::msgs::monotonic_us());
  hil::io::CanFrame frame;
  uint8_t noted = firmware_protocol::j1939::kNullAddress;
  while (!g_stop) {
    const int64_t now = rise::msgs::monotonic_us();
    if (!script.step(now, definition, emulator) || emulator.ended()) break;
    if (!bus.is_open()) {
      bus.reopen();
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      continue;
    }
    emulator.tick(bus, now);
    if (emulator.address() != noted) {
      noted = emulator.address();
      spdlog::info("J1939 address {:#04x} {}", noted, noted == 254 ? "(none: lost to a lower NAME)" : "claimed");
    }
    while (bus.is_open() && bus.receive(frame, 1) == hil::io::IoStatus::Ok)
      emulator.on_frame(bus, frame, rise::msgs::monotonic_us());
  }
  spdlog::info("rise-panel stopped: {} frames sent", emulator.frames_sent());
  return 0;
}

int run_emulate(const EmulateOptions& o) {
  using namespace rise;
  panels::PanelDefinition definition;
  panels::Timeline timeline;
  std::size_t source = 0;
  try {
    definition = panels::load_panel_definition(panels::find_data_file(o.panel));
    if (!o.source.empty()) {
      const auto s = definition.find_source(o.source);
      if (!s) throw std::runtime_error(definition.file + ": no source named '" + o.source + "'");
      source = *s;
    }
    if (!o.script.empty()) timeline = panels::load_timeline(panels::find_data_file(o.script), definition);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);
  if (!o.hid_file.empty()) return run_emulate_hid(o, definition, source, timeline);

  std::unique_ptr<hil::io::CanBus> bus;
  std::unique_ptr<hil::io::ModbusServer> server;
  try {
    if (o.modbus_url.empty())
      bus = hil::io::open_can_bus(o.can_url);
    else
      server = std::make_unique<hil::io::ModbusServer>(o.modbus_url, panels::ConsoleEmulator::modbus_table_sizes());
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  if (bus && definition.sources[source].is_canopen())
    return run_emulate_canopen(o, definition, source, timeline, *bus);
  if (definition.sources[source].is_j1939()) {
    if (bus) return run_emulate_j1939(o, definition, source, timeline, *bus);
    spdlog::error("source '{}' speaks j1939: it runs on CAN (--can), not Modbus", definition.sources[source].name);
    return 2;
  }
  panels::ConsoleEmulator emulator(definition, source);

  const uint16_t port = server ? server->port() : hil::io::listening_port(*bus);
  spdlog::info("rise-panel ready: emulating '{}' source '{}' (node {}) on {}{}{}", definition.name,
               definition.sources[source].name, definition.sources[source].node,
               server ? o.modbus_url : o.can_url, port ? " port " : "", port ? std::to_string(port) : "");

  ScriptClock script(timeline, o);
  script.start(rise::msgs::monotonic_us());
  hil::io::CanFrame frame;
  int64_t next_reopen_us = 0;
  bool started = !o.start_on_feedback;
  while (!g_stop) {
    const int64_t now = rise::msgs::monotonic_us();
    // The firmware runs from power-up; the scripted person starts once the
    // host is there (its first feedback frame), so runs are repeatable.
    if (!started) {
      script.start(now);
      if (emulator.feedback().frames > 0) {
        started = true;
        spdlog::info("host connected: script starts");
      }
    }
    if (!script.step(now, definition, emulator)) break;
    if (emulator.ended()) break;
    if (server) {
      // Modbus: the firmware cycle writes the registers; the host's writes
      // are read back as the console's feedback.
      emulator.tick_modbus(*server, now);
      if (emulator.poll_modbus_feedback(*server)) spdlog::info("feedback: {}", emulator.feedback_text());
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    if (!bus->is_open()) {
      if (now >= next_reopen_us) {
        bus->reopen();
        next_reopen_us = now + 200000;
      }
    } else {
      emulator.tick(*bus, now);
    }
    // Drain feedback until the next millisecond tick.
    while (bus->is_open() && bus->receive(frame, 1) == hil::io::IoStatus::Ok)
      if (emulator.on_frame(frame)) spdlog::info("feedback: {}", emulator.feedback_text());
    if (!bus->is_open()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  spdlog::info("rise-panel stopped: {} frames sent, {} feedback frames received ({} bad)",
               emulator.frames_sent(), emulator.feedback().frames, emulator.feedback().bad_frames);
  return 0;
}
}  // namespace

// `rise-panel check`: 0 when every file loads, else 1 (the loader's message per file).
int check_definitions(const std::vector<std::string>& files) {
  int code = 0;
  for (const auto& file : files) {
    try {
      const auto def = rise::panels::load_panel_definition(file);
      std::printf("%s: ok: panel %s, %zu sources, %zu controls\n", file.c_str(), def.name.c_str(), def.sources.size(),
                  def.controls.size());
    } catch (const std::exception& e) {
      std::printf("%s\n", e.what());
      code = 1;
    }
  }
  return code;
}

int main(int argc, char** argv) {
  CLI::App app{"rise-panel: console emulators and tools for the RISE console protocol"};
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")->capture_default_str();

  EmulateOptions emulate;
  CLI::App* em = app.add_subcommand(
      "emulate", "act as the console's firmware on a CAN transport (rise-can-v1, or a CANopen node from its EDS for a canopen source), as a Modbus slave, or as a HID device (uhid)");
  em->add_option("--panel", emulate.panel, "panel definition (YAML)")->capture_default_str();
  em->add_option("--source", emulate.source, "which source of the panel to emulate (default: the first)");
  CLI::Option* can_option = em->add_option("--can", emulate.can_url,
                 "transport: socketcand+listen://HOST:PORT/BUS (serve), socketcand://HOST:PORT/BUS, "
                 "socketcan://IFACE, mem://NAME")
      ->capture_default_str();
  em->add_option("--modbus", emulate.modbus_url,
                 "serve rise-modbus-v1 instead: modbus+tcp-listen://HOST:PORT?unit=N (PORT 0: any free port), "
                 "modbus+rtu-listen:///dev/pts/N?baud=B&unit=N")
      ->excludes(can_option);
  em->add_option("--hid", emulate.hid_file,
                 "be a HID device through /dev/uhid, described by this report descriptor (hex dump, C array, "
                 "hid-recorder R: lines, Android CTS register JSON, xpadneo markdown, binary); the source must be "
                 "protocol hid, its controls' signals names of the descriptor's input reports")
      ->excludes(can_option)
      ->excludes("--modbus");
  em->add_option("--hid-id", emulate.hid_id,
                 "VID:PID in hex (default: the descriptor file's, else the source's device: URL)")
      ->needs("--hid");
  em->add_option("--hid-name", emulate.hid_name, "product string (default: the descriptor file's name)")
      ->needs("--hid");
  em->add_option("--hid-period-ms", emulate.hid_period_ms,
                 "input reports are repeated at this period, and sent at once on change (0: only on change)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0))
      ->needs("--hid");
  em->add_option("--j1939-address", emulate.j1939_address,
                 "a j1939 source: the address the console claims (default: the definition's console_address)")
      ->check(CLI::Range(0, 253));
  em->add_option("--script", emulate.script, "timeline file: 'time control value' lines");
  em->add_flag("--loop", emulate.loop, "repeat the script");
  em->add_flag("--hold", emulate.hold, "keep sending the last state after the script ends");
  em->add_flag("--start-on-feedback", emulate.start_on_feedback,
               "start the script's clock at the first feedback frame from the host (HID: when the host opens "
               "the device)");

  rise::panels::ReplayOptions replay;
  CLI::App* rp = app.add_subcommand("replay", "play a CAN capture onto a live transport, like canplayer");
  rise::panels::add_replay_options(*rp, replay);

  std::vector<std::string> check_files;
  CLI::App* ck = app.add_subcommand("check", "load panel definitions as rise-hild --panel does; each error with file:line and key");
  ck->add_option("files", check_files, "panel definitions (YAML)")->required();

  if (const auto code = rise::cli::parse_command_line(app, "rise-panel", argc, argv)) return *code;
  spdlog::set_level(spdlog::level::from_str(log_level));
  if (em->parsed()) return run_emulate(emulate);
  if (ck->parsed()) return check_definitions(check_files);
  if (rp->parsed()) {
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::signal(SIGPIPE, SIG_IGN);
    return rise::panels::run_replay(replay, g_stop);
  }
  return 1;
}
