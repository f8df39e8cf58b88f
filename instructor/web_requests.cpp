#include "instructor/web_requests.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>

#include "instructor/fault_presets.hpp"

namespace rise::instructor {
namespace {

// body[key], or nullptr when absent or null (body is an object).
const Json::Value* member(const Json::Value& body, const char* key) {
  const Json::Value* v = body.find(key, key + std::strlen(key));
  return v && !v->isNull() ? v : nullptr;
}

bool refuse(std::string* error, const std::string& text) {
  *error = text;
  return false;
}

bool string_member(const Json::Value& body, const char* key, std::string& out, std::string* error) {
  const Json::Value* v = member(body, key);
  if (!v) return true;
  if (!v->isString()) return refuse(error, std::string("body: '") + key + "' must be a string");
  out = v->asString();
  // A NUL would end the string in the LCM message (msgs/lcm_gen.sh).
  if (out.find('\0') != std::string::npos) return refuse(error, std::string("body: '") + key + "' holds a NUL");
  return true;
}

bool number_member(const Json::Value& body, const char* key, double& out, std::string* error) {
  const Json::Value* v = member(body, key);
  if (!v) return true;
  if (!v->isDouble() || !std::isfinite(v->asDouble()))
    return refuse(error, std::string("body: '") + key + "' must be a finite number");
  out = v->asDouble();
  return true;
}

// body[key] as an object (or none); each member through take(name, value).
template <typename Take>
bool each_member(const Json::Value& body, const char* key, std::string* error, Take take) {
  const Json::Value* v = member(body, key);
  if (!v) return true;
  if (!v->isObject()) return refuse(error, std::string("body: '") + key + "' must be an object");
  for (auto it = v->begin(); it != v->end(); ++it)
    if (!take(it.name(), *it)) return refuse(error, std::string("body: '") + key + "." + it.name() + "': " + *error);
  return true;
}

bool trainee_member(const Json::Value& body, std::string& id, std::string* error) {
  if (!string_member(body, "trainee", id, error)) return false;
  if (!valid_trainee_id(id)) return refuse(error, "trainee '" + id + "': letters, digits, _ . - only");
  return true;
}

// The fault an inject names: a preset, or the body's own fields. False when it names neither.
bool fault_fields(const Json::Value& body, const std::string& name, rise_msgs::FaultCommand& c, std::string* error) {
  if (const FaultPreset* preset = find_fault_preset(name)) {
    c.kind = preset->kind;
    c.target = preset->target;
    c.value = preset->value;
    c.rate = preset->rate;
    c.duration_s = preset->duration_s;
    return true;
  }
  if (!member(body, "kind")) return refuse(error, "fault '" + name + "': no such preset, and no kind given");
  return string_member(body, "kind", c.kind, error) && string_member(body, "target", c.target, error) &&
         number_member(body, "value", c.value, error) && number_member(body, "rate", c.rate, error) &&
         number_member(body, "duration_s", c.duration_s, error);
}

}  // namespace

bool valid_trainee_id(const std::string& id) {
  const auto allowed = [](char ch) {
    return (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' ||
           ch == '.' || ch == '-';
  };
  return !id.empty() && id.size() <= 64 && std::all_of(id.begin(), id.end(), allowed);
}

std::string cookie_token(const std::string& cookies) {
  const std::string key = "rise_token=";
  for (std::size_t pos = 0; pos < cookies.size();) {
    std::size_t end = cookies.find(';', pos);
    if (end == std::string::npos) end = cookies.size();
    std::string part = cookies.substr(pos, end - pos);
    part.erase(0, part.find_first_not_of(' '));
    if (part.rfind(key, 0) == 0) return part.substr(key.size());
    pos = end + 1;
  }
  return "";
}

std::optional<Json::Value> parse_json_object(const std::string& body, std::string* error) {
  Json::CharReaderBuilder b;
  b["failIfExtra"] = true;
  Json::Value v;
  std::string errs;
  const std::unique_ptr<Json::CharReader> reader(b.newCharReader());
  try {
    if (!reader->parse(body.data(), body.data() + body.size(), &v, &errs)) {
      *error = "body: " + errs;
      return std::nullopt;
    }
  } catch (const std::exception& e) {  // jsoncpp throws past its nesting limit (stackLimit, 1000)
    *error = std::string("body: ") + e.what();
    return std::nullopt;
  }
  if (!v.isObject()) {
    *error = "body: not a JSON object";
    return std::nullopt;
  }
  return v;
}

std::optional<VirtualControls> virtual_controls_from_json(const Json::Value& body, std::string* error) {
  if (!body.isObject()) return refuse(error, "body: not a JSON object"), std::nullopt;
  VirtualControls c;
  const bool ok =
      each_member(body, "axes", error,
                  [&](const std::string& name, const Json::Value& v) {
                    if (!v.isDouble()) return refuse(error, "must be a number");
                    c.axes[name] = static_cast<float>(std::clamp(v.asDouble(), -1.0, 1.0));
                    return true;
                  }) &&
      each_member(body, "buttons", error,
                  [&](const std::string& name, const Json::Value& v) {
                    if (!v.isBool() && !v.isDouble()) return refuse(error, "must be true or false");
                    c.buttons[name] = v.isBool() ? v.asBool() : v.asDouble() != 0.0;
                    return true;
                  }) &&
      each_member(body, "switches", error, [&](const std::string& name, const Json::Value& v) {
        if (!v.isString()) return refuse(error, "must be a position's name");
        c.switches[name] = v.asString();
        return true;
      });
  if (!ok) return std::nullopt;
  return c;
}

std::optional<rise_msgs::FaultCommand> fault_command_from_json(const Json::Value& body, const std::string& action,
                                                              std::string* error) {
  if (!body.isObject()) return refuse(error, "body: not a JSON object"), std::nullopt;
  rise_msgs::FaultCommand c{};
  c.action = action;
  std::string name;
  if (!trainee_member(body, c.trainee_id, error) || !string_member(body, "fault", name, error)) return std::nullopt;
  c.fault_id = name == "*" ? "" : name;
  if (action != "inject") return c;
  if (!fault_fields(body, name, c, error)) return std::nullopt;
  if (c.fault_id.empty()) return refuse(error, "fault: a name is required to inject"), std::nullopt;
  c.seed = 1;
  if (const Json::Value* seed = member(body, "seed")) {
    if (!seed->isInt64()) return refuse(error, "body: 'seed' must be an integer"), std::nullopt;
    c.seed = seed->asInt64();
  }
  return c;
}

std::optional<ScenarioRequest> scenario_request_from_json(const Json::Value& body, bool start, std::string* error) {
  if (!body.isObject()) return refuse(error, "body: not a JSON object"), std::nullopt;
  ScenarioRequest r;
  if (!trainee_member(body, r.trainee, error)) return std::nullopt;
  if (!start) return r;
  if (!string_member(body, "file", r.file, error)) return std::nullopt;
  if (r.file.empty() || r.file.find_first_of(std::string("/\0", 2)) != std::string::npos ||
      std::filesystem::path(r.file).extension() != ".yaml")
    return refuse(error, "scenario file '" + r.file + "': not a .yaml file name"), std::nullopt;
  if (const Json::Value* seed = member(body, "seed")) {
    if (!seed->isUInt64()) return refuse(error, "body: 'seed' must be an integer >= 0"), std::nullopt;
    r.seed = seed->asUInt64();
  }
  return r;
}

}  // namespace rise::instructor
