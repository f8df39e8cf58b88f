#pragma once

// The panel as a source's thread reaches it: the bridge's PanelMapper under
// the bridge's lock. A source's transport (source_transport.hpp) feeds what
// it reads through update(); a change it reports wakes the publisher, which
// then publishes at once rather than at its next tick.

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "hil/panel_mapper.hpp"

namespace rise::hil {

/// What a bridge's source threads and its publisher share; `mutex` guards
/// all of it.
struct SharedPanel {
  explicit SharedPanel(panels::PanelDefinition definition) : mapper(std::move(definition)) {}
  PanelMapper mapper;
  mutable std::mutex mutex;
  std::condition_variable wake;          ///< the publisher waits on it
  bool changed = false;                  ///< a control changed: publish now, not at the next tick
  std::vector<std::string> notes;        ///< not yet taken (Bridge::take_notes)
  std::vector<std::string> notes_seen;   ///< every note once
};

/// One source's handle on a SharedPanel, used from that source's thread.
class SourcePanel {
 public:
  SourcePanel(SharedPanel& shared, std::size_t source) : shared_(shared), source_(source) {}

  std::size_t source() const { return source_; }
  const panels::PanelDefinition& definition() const { return shared_.mapper.definition(); }

  /// Runs apply(mapper, now_us) under the lock, now_us read under it
  /// (msgs::monotonic_us); apply returns true when a control changed, which
  /// publishes at once. Returns what apply returned. No allocation of its own.
  template <class Apply>
  bool update(Apply&& apply) {
    bool changed = false;
    {
      std::lock_guard lock(shared_.mutex);
      changed = apply(shared_.mapper, now_us());
      shared_.changed = shared_.changed || changed;
    }
    if (changed) shared_.wake.notify_all();
    return changed;
  }

  /// Something worth a line in the program's log that is no failsafe (an
  /// LED the device cannot show), kept once however often it is noted.
  /// Allocates.
  void note(std::string text);

 private:
  static int64_t now_us();

  SharedPanel& shared_;
  std::size_t source_;
};

}  // namespace rise::hil
