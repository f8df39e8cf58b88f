// Latency from a console frame entering the bridge's transport to the
// PanelState that carries it leaving on LCM (issue 3's figure): two
// processes on loopback. This program plays the console on a socketcand
// server (TCP, as a remote CAN bus or the emulator serves it), starts the
// real rise-hild as a child process, moves an axis to a new value every
// 5 ms and times each change until the PanelState with that value arrives
// back over LCM multicast. The figure therefore includes LCM's delivery
// back to this process: an upper bound on "frame in → PanelState out".
//
// usage: bench_frame_to_lcm_latency [SAMPLES]   (default 2000)

#include <lcm/lcm-cpp.hpp>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "firmware_protocol/console_can.hpp"
#include "hil/io/can_bus.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/lcm_decode.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"

namespace fp = rise::firmware_protocol;
using Clock = std::chrono::steady_clock;

namespace {
struct Listener {
  int64_t utime = 0;
  float drive_y = -2.0f;
  bool failsafe = true;
  Clock::time_point received;
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) {
    received = Clock::now();
    utime = m->utime;
    failsafe = m->failsafe;
    for (const auto& a : m->axes)
      if (a.name == "drive_y") drive_y = a.value;
  }
};

rise::hil::io::CanFrame to_can(const fp::WireFrame& w) {
  rise::hil::io::CanFrame f;
  f.id = w.can_id;
  f.len = 8;
  std::copy(w.data.begin(), w.data.end(), f.data.begin());
  return f;
}

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
}
}  // namespace

int main(int argc, char** argv) {
  const int samples = argc > 1 ? std::stoi(argv[1]) : 2000;
  const std::string lcm_url = rise::msgs::kDefaultLcmUrl;
  const std::string id = "bench" + std::to_string(::getpid());
  auto server = rise::hil::io::open_can_bus("socketcand+listen://127.0.0.1:0/can0?settle_ms=0");
  const uint16_t port = rise::hil::io::listening_port(*server);

  lcm::LCM lcm(lcm_url);
  Listener listener;
  rise::msgs::subscribe<&Listener::on>(lcm, rise::msgs::panel_state_channel(id), &listener)->setQueueCapacity(1000);

  const std::string bin = rise::process::executable_dir() + "/../bin/rise-hild";
  rise::process::ChildProcess hild({bin, "--panel", std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml",
                                "--can", "socketcand://127.0.0.1:" + std::to_string(port) + "/can0", "--id", id,
                                "--lcm", lcm_url, "--log-level", "warn"},
                               "/dev/null");

  fp::Encoder enc(0);
  int16_t axis = 0;
  auto send_all = [&] {
    server->send(to_can(enc.next(fp::HeartbeatFrame{1, fp::PanelStatus::Operational, 0})));
    server->send(to_can(enc.next(fp::AxesFrame{0, {0, axis, 0}})));
    server->send(to_can(enc.next(fp::AxesFrame{1, {0, 0, 0}})));
    server->send(to_can(enc.next(fp::ButtonsFrame{1u})));  // dead-man held
    fp::SwitchesFrame s;
    s.position = {0, 2, 0, 0, 0, 0};
    server->send(to_can(enc.next(s)));
  };
  auto pump = [&](int timeout_ms) {
    pollfd pfd{lcm.getFileno(), POLLIN, 0};
    if (::poll(&pfd, 1, timeout_ms) > 0) lcm.handle();
  };
  rise::hil::io::CanFrame dummy;
  auto drain_feedback = [&] {
    while (server->receive(dummy, 0) == rise::hil::io::IoStatus::Ok) {
    }
  };

  // Wait (deadline) until the daemon is connected and the panel healthy.
  const auto ready_deadline = Clock::now() + std::chrono::seconds(10);
  while (listener.failsafe && Clock::now() < ready_deadline) {
    send_all();
    drain_feedback();
    pump(10);
  }
  if (listener.failsafe) {
    std::fprintf(stderr, "rise-hild did not become healthy within 10 s\n");
    return 1;
  }

  std::vector<double> latency_us;
  int lost = 0;
  auto next_full = Clock::now();
  for (int i = 0; i < samples; ++i) {
    if (Clock::now() >= next_full) {  // keep every frame type fresh (heartbeat etc.)
      send_all();
      next_full = Clock::now() + std::chrono::milliseconds(20);
    }
    axis = static_cast<int16_t>(((i * 7919) % 60000) - 30000);
    const float expected = fp::axis_to_unit(axis);
    const auto t_send = Clock::now();
    const int64_t send_wall_us = rise::msgs::wall_us();
    server->send(to_can(enc.next(fp::AxesFrame{0, {0, axis, 0}})));
    bool got = false;
    while (Clock::now() - t_send < std::chrono::milliseconds(100)) {
      pump(1);
      // drive_y has a 0.05 deadband: compare after the same transform.
      const float x = expected;
      const float mapped = std::fabs(x) <= 0.05f ? 0.0f : std::copysign((std::fabs(x) - 0.05f) / 0.95f, x);
      if (!listener.failsafe && std::fabs(listener.drive_y - mapped) < 1e-5f) {
        latency_us.push_back(std::chrono::duration<double, std::micro>(listener.received - t_send).count());
        if (std::getenv("RISE_BENCH_DEBUG") && i < 10)
          std::printf("send→publish %lld us\n", static_cast<long long>(listener.utime - send_wall_us));
        got = true;
        break;
      }
    }
    if (!got) ++lost;
    drain_feedback();
    // 5 ms between changes: above the daemon's 1 ms publish-on-change gap.
    const auto until = t_send + std::chrono::milliseconds(5);
    while (Clock::now() < until) pump(1);
  }
  hild.stop();
  if (latency_us.empty()) {
    std::fprintf(stderr, "no sample arrived\n");
    return 1;
  }
  std::printf("frame → PanelState latency, rise-hild in its own process, socketcand (TCP loopback) in, "
              "LCM udpm out\n");
  std::printf("samples %zu (lost %d)\n", latency_us.size(), lost);
  std::printf("p50 %.0f us   p99 %.0f us   max %.0f us\n", percentile(latency_us, 0.5), percentile(latency_us, 0.99),
              *std::max_element(latency_us.begin(), latency_us.end()));
  std::printf("goal (issue 3): p99 < 1000 us\n");
  return 0;
}
