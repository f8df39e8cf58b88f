#pragma once

// What the web console's requests carry, read from the untrusted request:
// the token in a Cookie header, a trainee id, and the JSON bodies of the
// virtual panel's updates, the fault buttons and scenario control, each
// turned into what the handler acts on or into the 400 reply's text. Pure:
// no I/O; never throws (a body of the wrong shape is an error text). Fuzzed
// by tests/fuzz/web_requests_fuzz.cpp.

#include <json/json.h>

#include <cstdint>
#include <optional>
#include <string>

#include "instructor/virtual_controls.hpp"
#include "rise_msgs/FaultCommand.hpp"

namespace rise::instructor {

/// Letters, digits, _ . - only; 1 to 64 of them.
bool valid_trainee_id(const std::string& id);

/// The value of the Cookie header's rise_token= ("" when absent).
std::string cookie_token(const std::string& cookie_header);

/// The request body as a JSON object; nullopt with *error set ("body: ...").
std::optional<Json::Value> parse_json_object(const std::string& body, std::string* error);

/// POST /api/virtual/ID: {"axes": {NAME: number}, "buttons": {NAME: bool},
/// "switches": {NAME: "position"}}, each optional. Axes are clamped to -1..1.
std::optional<VirtualControls> virtual_controls_from_json(const Json::Value& body, std::string* error);

/// POST /api/fault/inject or /api/fault/clear (`action` "inject" or "clear"):
/// {"trainee": ID, "fault": NAME or "*" (clear: every one)} and, to inject
/// a fault that is not a preset, kind, target, value, rate, duration_s;
/// seed (inject, default 1). Fills trainee_id, action, fault_id, kind,
/// target, value, rate, duration_s, seed; the handler stamps and signs it.
std::optional<rise_msgs::FaultCommand> fault_command_from_json(const Json::Value& body, const std::string& action,
                                                              std::string* error);

/// POST /api/scenario/start or /stop: {"trainee": ID} and, to start, "file":
/// a .yaml file name (no folder) and an optional "seed".
struct ScenarioRequest {
  std::string trainee;
  std::string file;             ///< start only
  std::optional<uint64_t> seed;  ///< none: the file's
};
std::optional<ScenarioRequest> scenario_request_from_json(const Json::Value& body, bool start, std::string* error);

}  // namespace rise::instructor
