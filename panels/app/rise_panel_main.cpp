// rise-panel: the console's firmware emulated on a real transport, played
// from a scripted timeline.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <csignal>
#include <thread>

#include "hil/io/can_bus.hpp"
#include "hil/io/modbus_server.hpp"
#include "panels/app/replay_command.hpp"
#include "panels/console_emulator.hpp"
#include "panels/data_path.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

int64_t monotonic_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct EmulateOptions {
  std::string panel = "panels/definitions/rise_console.yaml";
  std::string source;
  std::string can_url = "socketcand+listen://127.0.0.1:29536/can0";
  std::string modbus_url;  ///< set: serve rise-modbus-v1 instead of CAN
  std::string script;
  bool loop = false;
  bool hold = false;
  bool start_on_feedback = false;
};

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

  std::unique_ptr<io::CanBus> bus;
  std::unique_ptr<io::ModbusServer> server;
  try {
    if (o.modbus_url.empty())
      bus = io::open_can_bus(o.can_url);
    else
      server = std::make_unique<io::ModbusServer>(o.modbus_url, panels::ConsoleEmulator::modbus_table_sizes());
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  panels::ConsoleEmulator emulator(definition, source);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);

  const uint16_t port = server ? server->port() : io::listening_port(*bus);
  spdlog::info("rise-panel ready: emulating '{}' source '{}' (node {}) on {}{}{}", definition.name,
               definition.sources[source].name, definition.sources[source].node,
               server ? o.modbus_url : o.can_url, port ? " port " : "", port ? std::to_string(port) : "");

  int64_t start_us = monotonic_us();
  std::size_t next_event = 0;
  io::CanFrame frame;
  int64_t next_reopen_us = 0;
  bool started = !o.start_on_feedback;
  while (!g_stop) {
    const int64_t now = monotonic_us();
    // The firmware runs from power-up; the scripted person starts once the
    // host is there (its first feedback frame), so runs are repeatable.
    if (!started) {
      start_us = now;
      if (emulator.feedback().frames > 0) {
        started = true;
        spdlog::info("host connected: script starts");
      }
    }
    const double t = static_cast<double>(now - start_us) * 1e-6;
    while (next_event < timeline.events.size() && timeline.events[next_event].time_s <= t) {
      const auto& e = timeline.events[next_event++];
      emulator.apply(e);
      if (e.kind == panels::TimelineEvent::Kind::Set) {
        const auto& c = definition.controls[e.control];
        spdlog::debug("t={:.2f} {} set", t, c.name);
      } else {
        spdlog::info("t={:.2f} {}:{} directive", t, timeline.file, e.line);
      }
    }
    if (emulator.ended()) break;
    if (next_event >= timeline.events.size() && !timeline.events.empty() && o.loop) {
      start_us = now;
      next_event = 0;
    } else if (next_event >= timeline.events.size() && !o.hold && !timeline.events.empty() &&
               !o.loop && t > timeline.end_time_s() + 0.5) {
      break;
    }
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
    while (bus->is_open() && bus->receive(frame, 1) == io::IoStatus::Ok)
      if (emulator.on_frame(frame)) spdlog::info("feedback: {}", emulator.feedback_text());
    if (!bus->is_open()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  spdlog::info("rise-panel stopped: {} frames sent, {} feedback frames received ({} bad)",
               emulator.frames_sent(), emulator.feedback().frames, emulator.feedback().bad_frames);
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rise-panel: console emulators and tools for the RISE console protocol"};
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")->capture_default_str();

  EmulateOptions emulate;
  CLI::App* em = app.add_subcommand("emulate", "act as the console's firmware on a CAN transport or as a Modbus slave");
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
  em->add_option("--script", emulate.script, "timeline file: 'time control value' lines");
  em->add_flag("--loop", emulate.loop, "repeat the script");
  em->add_flag("--hold", emulate.hold, "keep sending the last state after the script ends");
  em->add_flag("--start-on-feedback", emulate.start_on_feedback,
               "start the script's clock at the first feedback frame from the host");

  rise::panels::ReplayOptions replay;
  CLI::App* rp = app.add_subcommand("replay", "play a CAN capture onto a live transport, like canplayer");
  rise::panels::add_replay_options(*rp, replay);

  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  if (em->parsed()) return run_emulate(emulate);
  if (rp->parsed()) {
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::signal(SIGPIPE, SIG_IGN);
    return rise::panels::run_replay(replay, g_stop);
  }
  return 1;
}
