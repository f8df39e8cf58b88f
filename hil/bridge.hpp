#pragma once

// The daemon's cyclic core: one thread per source running one loop for any
// transport (source_transport.hpp: CAN frames received, Modbus registers
// polled at the source's poll_hz, HID reports read), one publisher thread
// at the panel's rate that also publishes at once when a control changes.
// Snapshots go to a callback (the program publishes them on LCM).

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "hil/feedback.hpp"
#include "hil/io/can_bus.hpp"
#include "hil/panel_mapper.hpp"
#include "hil/source_panel.hpp"
#include "hil/source_schedule.hpp"
#include "hil/source_transport.hpp"
#include "msgs/clock.hpp"

namespace rise::hil {

struct BridgeSettings {
  int64_t feedback_period_ms = 100;  ///< feedback frames are repeated at this period and sent on change
  int64_t reopen_min_ms = 100;       ///< first retry after a lost transport, doubled up to reopen_max_ms
  int64_t reopen_max_ms = 2000;
  int64_t min_change_gap_us = 250;   ///< publish-on-change never faster than this (≤ 4 kHz)
  int64_t hid_enumerate_ms = 500;    ///< hot-plug: HID devices are enumerated this often while one is away
};

class Bridge {
 public:
  using PublishFn = std::function<void(const PanelSnapshot&)>;

  /// One bus per source of the definition, in the same order (each a
  /// CanSource, or a CanopenSource for a canopen source).
  Bridge(panels::PanelDefinition definition, std::vector<std::unique_ptr<io::CanBus>> buses,
         PublishFn publish, BridgeSettings settings = {});
  /// One transport per source of the definition, in the same order
  /// (source_factory.hpp opens them from URLs). Each is used only from its
  /// source's thread.
  Bridge(panels::PanelDefinition definition, std::vector<std::unique_ptr<SourceTransport>> transports,
         PublishFn publish, BridgeSettings settings = {});
  ~Bridge();
  Bridge(const Bridge&) = delete;
  Bridge& operator=(const Bridge&) = delete;

  void start();
  void stop();

  /// Thread-safe: the latest feedback request (from LCM).
  void set_feedback(FeedbackRequest request);
  /// Thread-safe: the state right now.
  PanelSnapshot snapshot() const;
  /// Thread-safe: what the bridge noticed since the last call that is worth
  /// a line in the log but is no failsafe (a hid source's LED its device
  /// cannot show), each once. The program logs them; allocates.
  std::vector<std::string> take_notes();
  const panels::PanelDefinition& definition() const { return panel_.mapper.definition(); }
  /// Thread-safe: PanelMapper::inject_input_fault, published at once.
  std::string inject_input_fault(InputFault fault);
  /// Thread-safe: PanelMapper::clear_input_faults at now, published at once.
  std::size_t clear_input_faults(const std::string& id);

 private:
  void source_loop(std::size_t source);
  // Builds and writes a source's feedback when `schedule` says it is due;
  // Ok when it is not.
  io::IoStatus write_feedback(SourcePanel& panel, SourceTransport& transport, FeedbackSchedule& schedule, bool polled);
  void publish_loop();
  /// What feedback needs, taken together under the lock: the state at
  /// now_us, the request and its version.
  struct FeedbackState {
    PanelSnapshot snapshot;
    FeedbackRequest request;
    uint64_t version = 0;
  };
  FeedbackState feedback_state(int64_t now_us);

  SharedPanel panel_;  // the mapper, its lock, the publisher's wake-up, the notes
  std::vector<std::unique_ptr<SourceTransport>> transports_;
  PublishFn publish_;
  BridgeSettings settings_;

  FeedbackRequest feedback_;  // guarded by panel_.mutex
  std::atomic<uint64_t> feedback_version_{0};  // written under panel_.mutex

  std::atomic<bool> running_{false};
  std::vector<std::thread> threads_;
};

}  // namespace rise::hil
