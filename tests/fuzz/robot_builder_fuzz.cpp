// libFuzzer target: the Robot Builder's request body and its in-place YAML
// editor (instructor/robot_builder.hpp, sim/yaml_edit.hpp), without a server.
// An input with a NUL is "YAML TEXT \0 EDITS JSON": the edits applied to that
// text (any YAML a robots folder may hold); else the input is the page's
// body, applied to the shipped skid4.yaml and checked by the loader rise-sim
// uses (its URDF beside it). None may throw; every error has a message; an
// edit that applies reads back as given, every other value unchanged.
#include <json/json.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "instructor/robot_builder.hpp"
#include "panels/yaml_reader.hpp"
#include "sim/yaml_edit.hpp"
#include "tests/fuzz/builder_fuzz.hpp"

namespace ins = rise::instructor;
namespace sim = rise::sim;

namespace {

const std::string kFile = std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml";

const std::string& shipped() {
  static const std::string text = rise::fuzz::file_text(kFile);
  return text;
}

std::optional<std::vector<sim::YamlEdit>> edits_of(const std::string& json) {
  Json::Value body;
  std::string parse_error, error;
  const std::unique_ptr<Json::CharReader> reader(Json::CharReaderBuilder().newCharReader());
  if (!reader->parse(json.data(), json.data() + json.size(), &body, &parse_error)) return std::nullopt;
  auto edits = ins::robot_edits_from_json(body.isObject() ? body["edits"] : body, &error);
  fuzz_check(edits.has_value() || !error.empty());
  return edits;
}

void edit_text(const std::string& text, const std::vector<sim::YamlEdit>& edits) {
  std::string out;
  try {
    out = sim::apply_yaml_edits(text, edits);
  } catch (const sim::YamlEditError& e) {
    fuzz_check(std::string(e.what()).size() > rise::panels::printable(e.path()).size() + 2);
    return;
  } catch (const std::runtime_error& e) {  // the text is no YAML
    fuzz_check(e.what()[0] != '\0');
    return;
  }
  if (edits.empty()) fuzz_check(out == text);
  // The last edit of each path reads back (apply_yaml_edits checks each as it goes).
  if (!edits.empty()) {
    bool found = false;
    for (const auto& s : sim::yaml_scalars(out)) found |= s.value == edits.back().value;
    fuzz_check(found);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::size_t nul = input.find('\0');
  if (nul != std::string::npos) {
    const auto edits = edits_of(input.substr(nul + 1));
    if (edits) edit_text(input.substr(0, nul), *edits);
    return 0;
  }
  const auto edits = edits_of(input);
  if (!edits) return 0;
  const ins::RobotCheck check = ins::check_robot(shipped(), *edits, kFile);
  for (const auto& e : check.errors) fuzz_check(!e.message.empty() || !e.key.empty());
  fuzz_check(check.errors.empty() == check.robot.has_value());
  if (check.robot) ins::robot_check_json(check);
  return 0;
}
