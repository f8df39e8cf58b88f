// libFuzzer target: the Console Builder's request body (the page's controls
// as JSON, instructor/console_builder.hpp), without a server: read, written
// into the shipped rise_console.yaml's text (panels/panel_writer.hpp) and
// checked by rise-hild's loader. None may throw; every error has a message
// and a line of the YAML it was given, and the control it names is one of
// them; a definition that loads reads back to the same controls, which
// write to the same text (what the page sends back unchanged saves
// unchanged).
#include <json/json.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "instructor/console_builder.hpp"
#include "panels/panel_writer.hpp"
#include "tests/fuzz/builder_fuzz.hpp"

namespace ins = rise::instructor;
namespace panels = rise::panels;

namespace {

const std::string kFile = std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml";

const std::string& shipped_text() {
  static const std::string text = rise::fuzz::file_text(kFile);
  return text;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Json::Value body;
  // The server takes only an object (web_requests.hpp parse_json_object).
  if (!rise::fuzz::parse_json(text, &body) || !body.isObject()) return 0;
  std::string error;
  const auto controls = ins::controls_from_json(body["controls"], &error);
  if (!controls) {
    fuzz_check(!error.empty());
    return 0;
  }
  const ins::ConsoleCheck check = ins::check_console(shipped_text(), *controls, kFile);
  fuzz_check(!check.yaml.empty());
  fuzz_check(check.lines.size() == controls->size());
  const Json::Value j = ins::check_json(check);
  for (const auto& e : j["errors"]) {
    fuzz_check(!e["message"].asString().empty());
    fuzz_check(e["line"].asInt() >= 0 && e["line"].asInt() <= rise::fuzz::line_count(check.yaml) + 1);
    fuzz_check(e["control"].asInt() >= -1 && e["control"].asInt() < static_cast<int>(controls->size()));
  }
  if (check.definition) {
    const auto again = panels::read_panel_controls(check.yaml, kFile);
    fuzz_check(again.size() == controls->size());
    std::string error2;
    const auto through_page = ins::controls_from_json(ins::controls_json(again), &error2);
    fuzz_check(through_page.has_value());
    fuzz_check(panels::write_panel_controls(check.yaml, *through_page) == check.yaml);
  }
  return 0;
}
