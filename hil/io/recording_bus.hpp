#pragma once

// A CanBus that records every frame it receives and sends, in candump's log
// format (`candump -l`: readable by canplayer, python-can, SavvyCAN and our
// replay://), while passing everything through to the bus it wraps. Each
// line ends in " R" (received) or " T" (sent), as candump -x and python-can
// write it, so a replay can leave out the frames the recorder's owner sent.

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "hil/io/can_bus.hpp"
#include "hil/io/candump_log.hpp"
#include "hil/io/record_file.hpp"

namespace rise::hil::io {

class RecordingBus final : public CanBus {
 public:
  /// Which time a received frame is logged with.
  enum class Stamp {
    Transport,  ///< the transport's own stamp (kernel, adapter, socketcand server); now if it has none
    Receive,    ///< the wall-clock time receive() returned it: when its reader acted on it
  };

  /// Records `bus` into `path` (created or truncated) with `interface` as
  /// the log's interface name. Throws std::runtime_error if the file cannot
  /// be created.
  RecordingBus(std::unique_ptr<CanBus> bus, const std::string& path, std::string interface,
               Stamp stamp = Stamp::Transport);
  ~RecordingBus() override;

  /// Both record the frame when the wrapped bus took or gave it; a write
  /// that fails (disk full) is counted in write_errors(), never thrown.
  /// No allocation once the line buffer has grown to a line's length.
  IoStatus send(const CanFrame& frame) override;
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  IoStatus reopen() override { return bus_->reopen(); }
  bool is_open() const override { return bus_->is_open(); }
  const std::string& url() const override { return bus_->url(); }
  std::string last_error() const override { return bus_->last_error(); }

  int64_t frames_recorded() const { return file_.lines(); }
  /// Writes or flushes that failed (a full disk): the frames are lost, the bus goes on.
  int64_t write_errors() const { return file_.errors(); }

 private:
  void record(const CanFrame& frame, CandumpDirection direction);

  std::unique_ptr<CanBus> bus_;
  Stamp stamp_;
  std::mutex mutex_;  // send and receive may come from two threads: guards file_ and line_
  RecordFile file_;
  std::string interface_;
  std::string line_;
};

}  // namespace rise::hil::io
