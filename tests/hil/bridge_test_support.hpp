#pragma once

// What the bridge tests share: the shipped console definition, the console
// emulator (panels/) running as firmware in its own thread, timeline events
// made in code, and a collector of published snapshots that waits on a
// condition (a deadline, never a sleep).

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "hil/bridge.hpp"
#include "hil/io/modbus_server.hpp"
#include "panels/console_emulator.hpp"
#include "msgs/clock.hpp"

namespace rise::hil::test {

inline panels::PanelDefinition console() {
  return panels::load_panel_definition(std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml");
}

/// A timeline event that sets a control (axis value or button state).
inline panels::TimelineEvent set(const panels::PanelDefinition& def, const char* control, float axis,
                                 bool pressed) {
  panels::TimelineEvent e;
  e.control = *def.find_control(control);
  e.axis = axis;
  e.pressed = pressed;
  return e;
}

/// The console's firmware on a CAN bus (by URL), at the firmware's real
/// frame rates, in its own thread.
class EmulatorThread {
 public:
  EmulatorThread(const panels::PanelDefinition& def, const std::string& bus_url, std::size_t source = 0)
      : emulator_(def, source), bus_(io::open_can_bus(bus_url)) {
    thread_ = std::thread([this] { run(); });
  }
  ~EmulatorThread() {
    running_ = false;
    thread_.join();
  }
  void apply(const panels::TimelineEvent& e) {
    std::lock_guard lock(mutex_);
    emulator_.apply(e);
  }
  panels::ConsoleFeedback feedback() {
    std::lock_guard lock(mutex_);
    return emulator_.feedback();
  }

 private:
  void run() {
    io::CanFrame f;
    int64_t next_reopen_us = 0;
    while (running_) {
      // Like rise-panel emulate: a lost transport is reopened (every 100 ms).
      if (!bus_->is_open()) {
        if (rise::msgs::monotonic_us() >= next_reopen_us) {
          bus_->reopen();
          next_reopen_us = rise::msgs::monotonic_us() + 100'000;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));  // the firmware's idle loop, not a sync
        continue;
      }
      {
        std::lock_guard lock(mutex_);
        emulator_.tick(*bus_, rise::msgs::monotonic_us());
      }
      while (bus_->receive(f, 1) == io::IoStatus::Ok) {
        std::lock_guard lock(mutex_);
        emulator_.on_frame(f);
      }
    }
  }
  std::mutex mutex_;
  panels::ConsoleEmulator emulator_;
  std::unique_ptr<io::CanBus> bus_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

/// The console's firmware serving the rise-modbus-v1 map from its own
/// Modbus server (TCP or RTU URL), one firmware cycle per millisecond loop.
class ModbusEmulatorThread {
 public:
  ModbusEmulatorThread(const panels::PanelDefinition& def, uint16_t port, std::size_t source = 0)
      : ModbusEmulatorThread(def, "modbus+tcp-listen://127.0.0.1:" + std::to_string(port) + "?unit=1", source) {}
  ModbusEmulatorThread(const panels::PanelDefinition& def, const std::string& url, std::size_t source = 0)
      : emulator_(def, source), server_(url, panels::ConsoleEmulator::modbus_table_sizes()) {
    thread_ = std::thread([this] { run(); });
  }
  ~ModbusEmulatorThread() {
    running_ = false;
    thread_.join();
  }
  uint16_t port() const { return server_.port(); }
  void apply(const panels::TimelineEvent& e) {
    std::lock_guard lock(mutex_);
    emulator_.apply(e);
  }
  panels::ConsoleFeedback feedback() {
    std::lock_guard lock(mutex_);
    return emulator_.feedback();
  }

 private:
  void run() {
    while (running_) {
      {
        std::lock_guard lock(mutex_);
        emulator_.tick_modbus(server_, rise::msgs::monotonic_us());
        emulator_.poll_modbus_feedback(server_);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // the firmware's idle loop, not a sync
    }
  }
  std::mutex mutex_;
  panels::ConsoleEmulator emulator_;
  io::ModbusServer server_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

/// Every snapshot the bridge published, in order.
struct Published {
  std::mutex mutex;
  std::condition_variable cv;
  std::vector<PanelSnapshot> snapshots;

  void add(const PanelSnapshot& s) {
    std::lock_guard lock(mutex);
    snapshots.push_back(s);
    cv.notify_all();
  }
  /// The first snapshot from index `from` on that satisfies pred, waiting up
  /// to timeout_ms for it.
  template <typename Pred>
  std::optional<PanelSnapshot> wait_for(Pred pred, int timeout_ms, std::size_t from = 0) {
    std::unique_lock lock(mutex);
    std::optional<PanelSnapshot> found;
    cv.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] {
      for (std::size_t i = from; i < snapshots.size(); ++i)
        if (pred(snapshots[i])) {
          found = snapshots[i];
          return true;
        }
      return false;
    });
    return found;
  }
  std::size_t size() {
    std::lock_guard lock(mutex);
    return snapshots.size();
  }
};

}  // namespace rise::hil::test
