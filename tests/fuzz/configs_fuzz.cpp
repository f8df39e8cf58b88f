// libFuzzer target: the YAML files a user writes — panel definitions,
// robots, worlds, tasks and instructor scenarios — each parsed from the
// same arbitrary text (a training graph's parser links the task executor
// and through it the simulator: not here). An error must be a std::runtime_error whose
// text starts with the file name (the loaders say "file:line: key: what");
// nothing may crash, hang or trigger a sanitizer.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "instructor/scenario.hpp"
#include "panels/panel_definition.hpp"
#include "sim/robot_description.hpp"
#include "sim/training/task_description.hpp"
#include "sim/world_description.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

// Runs one parser; a std::runtime_error must name the file.
template <typename Parse>
void parse_one(Parse parse) {
  try {
    parse();
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.yaml"));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  // The first byte picks the parser, so that each one sees whole inputs
  // (a seed for one kind of file mutates into the others' as well).
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  const std::string file = "fuzz.yaml";
  switch (data[0] % 5) {
    case 0: parse_one([&] { rise::panels::parse_panel_definition(text, file); }); break;
    case 1: parse_one([&] { rise::sim::parse_robot_description(text, file); }); break;
    case 2: parse_one([&] { rise::sim::parse_world_description(text, file); }); break;
    case 3: parse_one([&] { rise::sim::training::parse_task_description(text, file); }); break;
    default: parse_one([&] { rise::instructor::parse_scenario(text, file); }); break;
  }
  return 0;
}
