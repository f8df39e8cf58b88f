#pragma once

// The daemon's cyclic core: one thread per source (CAN: receive frames;
// Modbus: poll the register map at the source's poll_hz), one publisher
// thread at the panel's rate that also publishes at once when a control
// changes. Transport-agnostic: frames come from io::CanBus, register blocks
// from io::ModbusLink, snapshots go to a callback (the program publishes
// them on LCM).

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hil/feedback.hpp"
#include "hil/io/can_bus.hpp"
#include "hil/io/input_device.hpp"
#include "hil/io/modbus_link.hpp"
#include "hil/panel_mapper.hpp"

namespace rise::hil {

struct BridgeSettings {
  int64_t feedback_period_ms = 100;  ///< feedback frames are repeated at this period and sent on change
  int64_t reopen_min_ms = 100;       ///< first retry after a lost transport, doubled up to reopen_max_ms
  int64_t reopen_max_ms = 2000;
  int64_t min_change_gap_us = 250;   ///< publish-on-change never faster than this (≤ 4 kHz)
  int64_t hid_enumerate_ms = 500;    ///< hot-plug: HID devices are enumerated this often while one is away
};

/// Monotonic microseconds (steady clock).
int64_t monotonic_us();

/// The transport of one source: a CAN bus (rise-can-v1, dbc), a Modbus link
/// (rise-modbus-v1) or a HID device (hid: a HidDevice or a HidReplayDevice);
/// exactly one is set.
struct SourceTransport {
  std::unique_ptr<io::CanBus> can;
  std::unique_ptr<io::ModbusLink> modbus;
  std::unique_ptr<io::InputDevice> hid;
};

class Bridge {
 public:
  using PublishFn = std::function<void(const PanelSnapshot&)>;

  /// One bus per source of the definition, in the same order.
  Bridge(panels::PanelDefinition definition, std::vector<std::unique_ptr<io::CanBus>> buses,
         PublishFn publish, BridgeSettings settings = {});
  /// One transport per source of the definition, in the same order. Each
  /// Modbus link is used only from its source's thread.
  Bridge(panels::PanelDefinition definition, std::vector<SourceTransport> transports, PublishFn publish,
         BridgeSettings settings = {});
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
  const panels::PanelDefinition& definition() const { return mapper_.definition(); }
  /// Thread-safe: PanelMapper::inject_input_fault, published at once.
  std::string inject_input_fault(InputFault fault);
  /// Thread-safe: PanelMapper::clear_input_faults at now, published at once.
  std::size_t clear_input_faults(const std::string& id);

 private:
  void source_loop(std::size_t source);
  void modbus_source_loop(std::size_t source);
  void hid_source_loop(std::size_t source);
  bool report_modbus(std::size_t source, const io::ModbusResult& result);
  void publish_loop();
  void send_feedback(std::size_t source, const PanelSnapshot& snap, bool force);
  void note(std::string text);
  /// What feedback needs, taken together under the lock: the state at
  /// now_us, the request and its version.
  struct FeedbackState {
    PanelSnapshot snapshot;
    FeedbackRequest request;
    uint64_t version = 0;
  };
  FeedbackState feedback_state(int64_t now_us);

  PanelMapper mapper_;
  std::vector<std::unique_ptr<io::CanBus>> buses_;            // null for a Modbus source
  std::vector<std::unique_ptr<io::ModbusLink>> modbus_links_;  // null for a CAN source
  std::vector<std::unique_ptr<io::InputDevice>> hid_devices_;  // null unless a hid source
  PublishFn publish_;
  BridgeSettings settings_;

  mutable std::mutex mutex_;  // guards mapper_, feedback_, changed_
  std::condition_variable wake_;
  bool changed_ = false;
  FeedbackRequest feedback_;
  uint64_t feedback_version_ = 0;
  std::vector<std::string> notes_;       // not yet taken
  std::vector<std::string> notes_seen_;  // every note once

  std::atomic<bool> running_{false};
  std::vector<std::thread> threads_;
};

}  // namespace rise::hil
