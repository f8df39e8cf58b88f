#include "panels/app/replay_command.hpp"

#include <poll.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "hil/io/can_url.hpp"
#include "hil/io/candump_log.hpp"
#include "hil/io/replay_bus.hpp"
#include "hil/io/socketcand_server.hpp"

namespace rise::panels {
namespace {

std::string replay_url(const ReplayOptions& o) {
  std::string url = "replay://" + o.file + "?speed=" + std::to_string(o.speed) + "&loop=" + std::to_string(o.loop);
  if (o.start_s > 0.0) url += "&start=" + std::to_string(o.start_s);
  if (o.stop_s >= 0.0) url += "&stop=" + std::to_string(o.stop_s);
  if (!o.ids.empty()) url += "&ids=" + o.ids;
  if (!o.channel.empty()) url += "&channel=" + o.channel;
  if (o.fast) url += "&fast=1";
  if (o.step) url += "&step=1";
  return url;
}

}  // namespace

void add_replay_options(CLI::App& app, ReplayOptions& o) {
  app.add_option("file", o.file, "capture: candump log, Vector ASC or PEAK TRC")->required();
  app.add_option("--to", o.to,
                 "transport to play onto: socketcan://IFACE, slcan:///dev/ttyACM0?bitrate=N, "
                 "socketcand://HOST:PORT/BUS, socketcand+listen://HOST:PORT/BUS (serve it), mem://NAME")
      ->required();
  app.add_option("--speed", o.speed, "time scale (2 = twice as fast)")->capture_default_str();
  app.add_option("--loop", o.loop, "extra passes (-1: forever)")->capture_default_str();
  app.add_option("--start", o.start_s, "seconds from the first frame to start at");
  app.add_option("--stop", o.stop_s, "seconds from the first frame to stop at");
  app.add_option("--ids", o.ids, "only these ids, hex, comma-separated (123,1F334455)");
  app.add_option("--channel", o.channel, "only frames of this channel of the log (can0, 1)");
  app.add_flag("--fast", o.fast, "as fast as the transport takes them (frames keep their recorded times)");
  app.add_flag("--step", o.step, "one frame per Enter on standard input, printed as it goes");
  app.add_flag("--wait-peer", o.wait_peer, "socketcand+listen: start when the first client is in raw mode");
  app.add_option("--progress-every", o.progress_every_s, "seconds between progress lines (0: none)")
      ->capture_default_str();
}

int run_replay(const ReplayOptions& o, const volatile int& stop) {
  const std::string url = replay_url(o);
  std::unique_ptr<hil::io::ReplayBus> replay;
  std::unique_ptr<hil::io::CanBus> out;
  try {
    replay = std::make_unique<hil::io::ReplayBus>(url, std::get<hil::io::ReplayAddress>(hil::io::parse_can_url(url)));
    out = hil::io::open_can_bus(o.to);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  if (o.wait_peer) {
    auto* server = dynamic_cast<hil::io::SocketcandServer*>(out.get());
    if (!server) {
      spdlog::error("--wait-peer is for socketcand+listen:// transports, not {}", o.to);
      return 2;
    }
    spdlog::info("waiting for a socketcand client on {}", o.to);
    while (!stop && server->client_count() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  spdlog::info("replaying {} onto {}", o.file, o.to);

  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  auto next_progress = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.progress_every_s));
  uint64_t sent = 0, send_errors = 0;
  hil::io::CanFrame frame;
  while (!stop) {
    if (o.step) {
      // Enter lets the next frame out; end of input ends the replay.
      pollfd in{STDIN_FILENO, POLLIN, 0};
      if (::poll(&in, 1, 100) > 0) {
        char buffer[256];
        if (::read(STDIN_FILENO, buffer, sizeof buffer) <= 0) break;
        replay->step(1);
      }
    }
    const hil::io::IoStatus st = replay->receive(frame, 100);
    if (st == hil::io::IoStatus::Disconnected) break;  // end of the capture
    if (st == hil::io::IoStatus::Ok) {
      if (out->send(frame) == hil::io::IoStatus::Ok) {
        ++sent;
      } else {
        ++send_errors;
        if (!out->is_open()) out->reopen();
      }
      if (o.step) std::printf("%s\n", hil::io::format_candump_line(frame, "can0").c_str()), std::fflush(stdout);
    }
    if (o.progress_every_s > 0 && Clock::now() >= next_progress) {
      next_progress += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.progress_every_s));
      const auto p = replay->progress();
      spdlog::info("replay: {} frames sent, log time {:.1f} s, {:.0f} % of the file{}, max lateness {:.2f} ms", sent,
                   p.log_time_s, 100.0 * p.fraction, p.loops_done ? fmt::format(" (loop {})", p.loops_done) : "",
                   static_cast<double>(replay->max_lateness_us()) / 1e3);
    }
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  spdlog::info("rise-panel replay: {} frames sent in {:.2f} s ({} send errors, {} malformed lines, max lateness {:.2f} ms)",
               sent, wall_s, send_errors, replay->malformed_lines(),
               static_cast<double>(replay->max_lateness_us()) / 1e3);
  return 0;
}

}  // namespace rise::panels
