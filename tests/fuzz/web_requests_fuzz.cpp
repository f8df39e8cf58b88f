// libFuzzer target: what the instructor's web console reads from a request
// (instructor/web_requests.hpp), without a server: the input as a Cookie
// header and a trainee id, then as a JSON body given to every request's
// reader (the virtual panel's update, fault inject and clear, scenario start
// and stop). None may throw; what one accepts is what its handler may act
// on: a valid trainee id, axes within -1..1, finite fault parameters, a
// scenario file name without a folder ending in .yaml; an error is the 400
// reply's text.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "instructor/web_requests.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace ins = rise::instructor;

namespace {

void headers(const std::string& text) {
  const std::string token = ins::cookie_token(text);
  fuzz_check(token.find(';') == std::string::npos && text.find(token) != std::string::npos);
  if (ins::valid_trainee_id(text)) fuzz_check(!text.empty() && text.size() <= 64 && text.find('/') == std::string::npos);
}

void virtual_controls(const Json::Value& body) {
  std::string error;
  const auto c = ins::virtual_controls_from_json(body, &error);
  if (!c) {
    fuzz_check(error.starts_with("body: "));
    return;
  }
  for (const auto& [name, v] : c->axes) fuzz_check(std::isfinite(v) && v >= -1.0f && v <= 1.0f);
}

void fault(const Json::Value& body, const std::string& action) {
  std::string error;
  const auto c = ins::fault_command_from_json(body, action, &error);
  if (!c) {
    fuzz_check(!error.empty());
    return;
  }
  fuzz_check(ins::valid_trainee_id(c->trainee_id) && c->action == action);
  fuzz_check(std::isfinite(c->value) && std::isfinite(c->rate) && std::isfinite(c->duration_s));
  if (action == "inject") fuzz_check(!c->fault_id.empty());
}

void scenario(const Json::Value& body, bool start) {
  std::string error;
  const auto r = ins::scenario_request_from_json(body, start, &error);
  if (!r) {
    fuzz_check(!error.empty());
    return;
  }
  fuzz_check(ins::valid_trainee_id(r->trainee));
  if (!start) return;
  fuzz_check(r->file.size() > 5 && r->file.ends_with(".yaml"));
  fuzz_check(r->file.find('/') == std::string::npos && r->file.find('\0') == std::string::npos);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    headers(text);
    std::string error;
    const auto body = ins::parse_json_object(text, &error);
    if (!body) {
      fuzz_check(error.starts_with("body: "));
      return 0;
    }
    fuzz_check(body->isObject());
    virtual_controls(*body);
    fault(*body, "inject");
    fault(*body, "clear");
    scenario(*body, true);
    scenario(*body, false);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "web_requests_fuzz: threw %s\n", e.what());
    std::abort();
  }
  return 0;
}
