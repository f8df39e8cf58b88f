#include "msgs/failsafe.hpp"

namespace rise::msgs {

const char* to_string(FailsafeCause cause) {
  switch (cause) {
    case FailsafeCause::SourceDown: return "source down";
    case FailsafeCause::SourceStale: return "source stale";
    case FailsafeCause::ProtectionFailed: return "protection failed";
    case FailsafeCause::SourceError: return "source error";
    case FailsafeCause::ControlInvalid: return "control invalid";
    case FailsafeCause::InputFault: return "input fault";
    case FailsafeCause::Estop: return "e-stop";
  }
  return "unknown";
}

std::string to_string(FailsafeCauses causes) {
  std::string text;
  for (const FailsafeCause cause : kFailsafeCauses) {
    if (!causes.has(cause)) continue;
    if (!text.empty()) text += ", ";
    text += to_string(cause);
  }
  return text;
}

}  // namespace rise::msgs
