// Decode + map + publish throughput of the bridge on one core, as a ratio to
// a saturated 1 Mbit/s classic CAN bus (issue 3's figure).
//
// A saturated bus of 8-byte standard frames carries about 8,800 frames/s
// (111-bit frames plus worst-case stuffing ≈ 113 µs each). The benchmark
// feeds pre-encoded rise-can-v1 frames of a moving console into the same
// PanelMapper the daemon runs, three ways:
//   decode+map          on_frame() only (the receive thread's work)
//   +evaluate           plus the safety evaluation after every frame
//   +publish (memq)     plus PanelState built and published through LCM's
//                       in-process provider after every frame — the worst
//                       case where each frame changes a control.
//   daemon path         what rise-hild does: decode+map every frame, evaluate
//                       and publish on change at most once per min_change_gap_us (250 us).
// Prints frames/s and the ratio to 8,800 frames/s for each.

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "firmware_protocol/console_can.hpp"
#include "hil/bridge.hpp"
#include "hil/panel_mapper.hpp"
#include "hil/panel_state_message.hpp"
#include "panels/panel_definition.hpp"

namespace fp = rise::firmware_protocol;

namespace {
constexpr double kSaturatedBusFps = 8800.0;

std::vector<fp::WireFrame> console_traffic(std::size_t n) {
  fp::Encoder enc(0);
  std::vector<fp::WireFrame> frames;
  frames.reserve(n);
  for (std::size_t i = 0; frames.size() < n; ++i) {
    const auto v = static_cast<int16_t>((i * 37) % 65535 - 32767);
    switch (i % 5) {
      case 0: frames.push_back(enc.next(fp::HeartbeatFrame{1, fp::PanelStatus::Operational, static_cast<uint32_t>(i)})); break;
      case 1: frames.push_back(enc.next(fp::AxesFrame{0, {v, static_cast<int16_t>(-v), 0}})); break;
      case 2: frames.push_back(enc.next(fp::AxesFrame{1, {0, v, 0}})); break;
      case 3:  // dead-man held, gripper_open (button 2) toggling
        frames.push_back(enc.next(fp::ButtonsFrame{static_cast<uint32_t>(1u | ((i / 5) & 4u))})); break;
      default: {
        fp::SwitchesFrame s;
        s.position = {0, static_cast<uint8_t>((i / 5) % 3), 0, 0, 0, 0};
        frames.push_back(enc.next(s));
      }
    }
  }
  return frames;
}

template <typename F>
double frames_per_second(const std::vector<fp::WireFrame>& frames, F&& per_frame) {
  // Warm-up pass, then the timed pass.
  for (std::size_t i = 0; i < frames.size() / 10; ++i) per_frame(frames[i], static_cast<int64_t>(i));
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < frames.size(); ++i) per_frame(frames[i], static_cast<int64_t>(i));
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return static_cast<double>(frames.size()) / s;
}
}  // namespace

int main(int argc, char** argv) {
  const std::string panel = argc > 1 ? argv[1] : std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml";
  const auto def = rise::panels::load_panel_definition(panel);
  const auto frames = console_traffic(1'000'000);
  std::printf("decode + map + publish throughput, one core, %zu rise-can-v1 frames of a moving console\n",
              frames.size());
  std::printf("reference: saturated 1 Mbit/s classic CAN bus = %.0f frames/s (8-byte standard frames)\n\n",
              kSaturatedBusFps);

  // Each pass gets a fresh mapper; time advances 10 µs per frame so nothing goes stale.
  auto report = [&](const char* what, double fps) {
    std::printf("%-34s %12.0f frames/s  %8.1f x saturated bus\n", what, fps, fps / kSaturatedBusFps);
  };
  {
    rise::hil::PanelMapper mapper(def);
    mapper.on_connection(0, true, 0);
    int64_t changed = 0;
    report("decode+map", frames_per_second(frames, [&](const fp::WireFrame& f, int64_t i) {
             changed += mapper.on_frame(0, f.can_id, f.data, 1000 + i * 10);
           }));
    if (changed == 0) return 1;  // keeps the work observable
  }
  {
    rise::hil::PanelMapper mapper(def);
    mapper.on_connection(0, true, 0);
    int64_t failsafe = 0;
    report("decode+map+evaluate", frames_per_second(frames, [&](const fp::WireFrame& f, int64_t i) {
             mapper.on_frame(0, f.can_id, f.data, 1000 + i * 10);
             failsafe += mapper.evaluate(1000 + i * 10).failsafe;
           }));
    std::printf("%-34s %12lld of %zu evaluations failsafe (startup only)\n", "", static_cast<long long>(failsafe),
                frames.size());
  }
  {
    rise::hil::PanelMapper mapper(def);
    mapper.on_connection(0, true, 0);
    lcm::LCM lcm("memq://");
    if (!lcm.good()) return 1;
    int64_t seq = 0;
    const std::vector<std::string> urls{"bench://"};
    report("decode+map+evaluate+publish (memq)",
           frames_per_second(frames, [&](const fp::WireFrame& f, int64_t i) {
             mapper.on_frame(0, f.can_id, f.data, 1000 + i * 10);
             const auto snap = mapper.evaluate(1000 + i * 10);
             const auto msg = rise::hil::to_message(def, snap, "bench", seq++, i, urls);
             lcm.publish("rise/bench/panel_state", &msg);
             if (seq % 1000 == 0) lcm.handleTimeout(0);  // drain the in-process queue
           }));
  }
  {
    // What rise-hild does: every frame decoded and mapped in the receive
    // thread; the publisher evaluates and publishes on a change, at most once
    // per BridgeSettings::min_change_gap_us (250 us), plus its 100 Hz tick.
    rise::hil::PanelMapper mapper(def);
    mapper.on_connection(0, true, 0);
    lcm::LCM lcm("memq://");
    int64_t seq = 0, last_publish_us = -1'000'000;
    bool changed = false;
    const std::vector<std::string> urls{"bench://"};
    const int64_t gap_us = rise::hil::BridgeSettings{}.min_change_gap_us;
    const auto t0 = std::chrono::steady_clock::now();
    auto now_us = [&] {
      return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0).count();
    };
    report("daemon path (publish on change)", frames_per_second(frames, [&](const fp::WireFrame& f, int64_t) {
             const int64_t now = now_us();
             changed = mapper.on_frame(0, f.can_id, f.data, now) || changed;
             if (changed && now - last_publish_us >= gap_us) {
               const auto msg = rise::hil::to_message(def, mapper.evaluate(now), "bench", seq++, now, urls);
               lcm.publish("rise/bench/panel_state", &msg);
               lcm.handleTimeout(0);
               last_publish_us = now;
               changed = false;
             }
           }));
    std::printf("%-34s %12lld PanelState messages published\n", "", static_cast<long long>(seq));
  }
  std::printf("\ngoal (issue 3): >= 100 x saturated bus for decode + map + publish\n");
  return 0;
}
