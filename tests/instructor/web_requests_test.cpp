#include <catch2/catch.hpp>

#include <string>

#include "instructor/web_requests.hpp"

using namespace rise::instructor;

namespace {

Json::Value body_of(const std::string& text) {
  std::string error;
  const auto v = parse_json_object(text, &error);
  INFO(error);
  REQUIRE(v);
  return *v;
}

// The 400 text a fault request gets ("" when taken).
std::string fault_error(const std::string& text, const std::string& action = "inject") {
  std::string error;
  return fault_command_from_json(body_of(text), action, &error) ? "" : error;
}

}  // namespace

TEST_CASE("a request body must be one JSON object", "[instructor]") {
  std::string error;
  CHECK_FALSE(parse_json_object("{not json", &error));
  CHECK(error.rfind("body: ", 0) == 0);
  CHECK_FALSE(parse_json_object("[1, 2]", &error));
  CHECK(error == "body: not a JSON object");
  CHECK_FALSE(parse_json_object(R"({"a": 1} {"b": 2})", &error));
  CHECK(parse_json_object(" {\"a\": 1}\n", &error));
  // Found by the web_requests fuzz target: jsoncpp throws (not returns false)
  // past its nesting limit, so such a body was a 500.
  CHECK_FALSE(parse_json_object(std::string(1001, '[') + std::string(1001, ']'), &error));
  CHECK(error == "body: Exceeded stackLimit in readValue().");
}

TEST_CASE("trainee ids and the cookie's token", "[instructor]") {
  CHECK(valid_trainee_id("t1.a-b_C"));
  CHECK_FALSE(valid_trainee_id(""));
  CHECK_FALSE(valid_trainee_id("a/b"));
  CHECK_FALSE(valid_trainee_id(std::string(65, 'a')));
  CHECK(valid_trainee_id(std::string(64, 'a')));
  CHECK(cookie_token("a=b;  rise_token=xyz; c=d") == "xyz");
  CHECK(cookie_token("rise_token=") == "");
  CHECK(cookie_token("a=rise_token=1") == "");
}

TEST_CASE("a fault request becomes the command's fields, or the reason it is refused", "[instructor]") {
  std::string error;
  const auto preset = fault_command_from_json(body_of(R"({"trainee":"t1","fault":"stick-stuck"})"), "inject", &error);
  REQUIRE(preset);
  CHECK(preset->trainee_id == "t1");
  CHECK(preset->action == "inject");
  CHECK(preset->fault_id == "stick-stuck");
  CHECK(preset->kind == "stuck_at");
  CHECK(preset->seed == 1);
  const auto own = fault_command_from_json(
      body_of(R"({"trainee":"t1","fault":"f","kind":"noise","target":"drive_x","value":0.5,"rate":2,"seed":-7})"),
      "inject", &error);
  REQUIRE(own);
  CHECK(own->kind == "noise");
  CHECK(own->value == 0.5);
  CHECK(own->rate == 2.0);
  CHECK(own->seed == -7);
  const auto all = fault_command_from_json(body_of(R"({"trainee":"t1","fault":"*"})"), "clear", &error);
  REQUIRE(all);
  CHECK(all->fault_id.empty());
  CHECK(fault_error(R"({"trainee":"t1","fault":"nope"})") == "fault 'nope': no such preset, and no kind given");
  CHECK(fault_error(R"({"trainee":"a/b","fault":"stick-stuck"})") == "trainee 'a/b': letters, digits, _ . - only");
  CHECK(fault_error(R"({"trainee":"t1","fault":"*","kind":"noise"})") == "fault: a name is required to inject");
}

// Found writing the web_requests fuzz target (tests/fuzz/web_requests_fuzz.cpp):
// the handlers read these with jsoncpp's asString/asDouble/asInt64, which throw
// on a value of another type or range, so the request got a 500 (cpp-httplib's
// catch) instead of a 400 saying what is wrong.
TEST_CASE("a fault, scenario or virtual panel request with a value of the wrong type is a 400's text", "[instructor]") {
  CHECK(fault_error(R"({"trainee":["t1"],"fault":"stick-stuck"})") == "body: 'trainee' must be a string");
  CHECK(fault_error(R"({"trainee":"t1","fault":{}})") == "body: 'fault' must be a string");
  CHECK(fault_error(R"({"trainee":"t1","fault":"f","kind":"noise","value":"x"})") ==
        "body: 'value' must be a finite number");
  CHECK(fault_error(R"({"trainee":"t1","fault":"f","kind":1})") == "body: 'kind' must be a string");
  CHECK(fault_error(R"({"trainee":"t1","fault":"stick-stuck","seed":1e30})") == "body: 'seed' must be an integer");
  std::string error;
  CHECK_FALSE(scenario_request_from_json(body_of(R"({"trainee":"t1","file":"s.yaml","seed":-1})"), true, &error));
  CHECK(error == "body: 'seed' must be an integer >= 0");
  CHECK_FALSE(virtual_controls_from_json(body_of(R"({"axes":[1]})"), &error));
  CHECK(error == "body: 'axes' must be an object");
  CHECK_FALSE(virtual_controls_from_json(body_of(R"({"axes":{"drive_y":"up"}})"), &error));
  CHECK(error == "body: 'axes.drive_y': must be a number");
  CHECK_FALSE(virtual_controls_from_json(body_of(R"({"switches":{"mode":2}})"), &error));
  CHECK(error == "body: 'switches.mode': must be a position's name");
}

TEST_CASE("a virtual panel's controls and a scenario request", "[instructor]") {
  std::string error;
  const auto c = virtual_controls_from_json(
      body_of(R"({"axes":{"drive_y":0.8,"drive_x":1e300},"buttons":{"deadman":true,"horn":0},"switches":{"mode":"arm"}})"),
      &error);
  REQUIRE(c);
  CHECK(c->axes.at("drive_y") == 0.8f);
  CHECK(c->axes.at("drive_x") == 1.0f);  // clamped, not a float overflow
  CHECK(c->buttons.at("deadman"));
  CHECK_FALSE(c->buttons.at("horn"));
  CHECK(c->switches.at("mode") == "arm");
  const auto start = scenario_request_from_json(body_of(R"({"trainee":"t1","file":"stuck.yaml","seed":11})"), true, &error);
  REQUIRE(start);
  CHECK(start->file == "stuck.yaml");
  CHECK(start->seed == 11u);
  const auto stop = scenario_request_from_json(body_of(R"({"trainee":"t1"})"), false, &error);
  REQUIRE(stop);
  CHECK_FALSE(stop->seed);
  for (const char* bad : {R"({"trainee":"t1","file":"../x.yaml"})", R"({"trainee":"t1","file":"x.yml"})",
                          R"({"trainee":"t1","file":".yaml"})", R"({"trainee":"t1","file":"x\u0000.yaml"})"}) {
    CHECK_FALSE(scenario_request_from_json(body_of(bad), true, &error));
    CHECK((error.find("not a .yaml file name") != std::string::npos || error == "body: 'file' holds a NUL"));
  }
}
