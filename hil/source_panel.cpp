#include "hil/source_panel.hpp"

#include <algorithm>
#include <utility>

#include "hil/bridge.hpp"
#include "msgs/clock.hpp"

namespace rise::hil {

void SourcePanel::note(std::string text) {
  std::lock_guard lock(shared_.mutex);
  if (std::find(shared_.notes_seen.begin(), shared_.notes_seen.end(), text) != shared_.notes_seen.end()) return;
  shared_.notes_seen.push_back(text);
  shared_.notes.push_back(std::move(text));
}

int64_t SourcePanel::now_us() { return msgs::monotonic_us(); }

}  // namespace rise::hil
