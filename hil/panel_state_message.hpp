#pragma once

// PanelSnapshot ⇄ the LCM contract (msgs/lcmtypes).

#include <string>

#include "hil/feedback.hpp"
#include "hil/panel_mapper.hpp"
#include "rise_msgs/PanelFeedback.hpp"
#include "rise_msgs/PanelState.hpp"

namespace rise::hil {

/// Fills a PanelState from a snapshot. `utime` is wall-clock microseconds.
rise_msgs::PanelState to_message(const panels::PanelDefinition& definition,
                                 const PanelSnapshot& snapshot, const std::string& trainee_id,
                                 int64_t seq, int64_t utime,
                                 const std::vector<std::string>& source_urls);

/// Reads a PanelFeedback message into a request for build_feedback().
FeedbackRequest from_message(const rise_msgs::PanelFeedback& message);

}  // namespace rise::hil
