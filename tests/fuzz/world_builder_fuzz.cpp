// libFuzzer target: the Environment Builder (instructor/world_builder.hpp,
// sim/world_writer.hpp), without a server. A byte first: 0, the page's body
// (the world as JSON): read, written as YAML with the comments of the shipped
// building and loaded by rise-sim's loader; none may throw, an error has a
// message and a line of the YAML it was given, and a world that loads goes
// through the page's JSON and back to the same text (what the page sends
// back unchanged saves unchanged). Else a world file: its comments read, and
// a world that loads is written (with them) as a text that loads again.
#include <json/json.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "instructor/world_builder.hpp"
#include "panels/yaml_reader.hpp"
#include "sim/world_writer.hpp"
#include "tests/fuzz/builder_fuzz.hpp"

namespace ins = rise::instructor;
namespace sim = rise::sim;

namespace {

const std::string kFile = "fuzz_world.yaml";

const std::string& building_text() {
  static const std::string text = rise::panels::read_text_file(std::string(RISE_SOURCE_DIR) + "/sim/worlds/building.yaml");
  return text;
}

void page_body(const std::string& text) {
  Json::Value body;
  if (!rise::fuzz::parse_json(text, &body)) return;
  std::string error;
  const auto world = ins::world_model_from_json(body, &error);
  if (!world) {
    fuzz_check(!error.empty());
    return;
  }
  const ins::WorldCheck check = ins::check_world(*world, kFile, building_text());
  fuzz_check(!check.yaml.empty());
  fuzz_check(check.loaded.has_value() == check.errors.empty());
  rise::fuzz::check_builder_errors(check.errors, check.yaml);
  if (!check.loaded) return;
  const auto again = ins::world_model_from_json(ins::world_model_json(*check.loaded), &error);
  fuzz_check(again.has_value());
  fuzz_check(sim::write_world(*again, sim::read_world_comments(building_text())) == check.yaml);
}

void world_file(const std::string& text) {
  const sim::WorldComments comments = sim::read_world_comments(text);
  sim::WorldDescription w;
  try {
    w = sim::parse_world_description(text, kFile);
  } catch (const std::exception&) {
    return;
  }
  const std::string written = sim::write_world(w, comments);
  try {
    sim::parse_world_description(written, kFile);
  } catch (const std::exception& e) {
    fuzz_check(false);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  if (data[0] == 0) page_body(text);
  else world_file(text);
  return 0;
}
