// libFuzzer target: the Task Builder's request body (the page's task as
// JSON, instructor/task_builder.hpp), without a server: read, written as
// YAML (sim/training/task_writer.hpp) and checked as rise-trainer check
// checks a task beside the shipped ones (the loader, then the world). None
// may throw; every error has a message, and one in the task names a line of
// the YAML it was given; a YAML that loads goes through the page's JSON and
// back to the same text (what the page sends back unchanged saves unchanged).
#include <json/json.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "instructor/task_builder.hpp"
#include "sim/training/task_writer.hpp"
#include "tests/fuzz/builder_fuzz.hpp"

namespace ins = rise::instructor;
namespace training = rise::sim::training;

namespace {

// Beside the shipped task files, so that ../../worlds/building.yaml resolves.
const std::string kFile = std::string(RISE_SOURCE_DIR) + "/sim/training/examples/fuzz_task.yaml";

void json_round_trip(const std::string& yaml) {
  training::TaskDescription loaded;
  try {
    loaded = training::parse_task_description(yaml, kFile);
  } catch (const std::exception&) {
    return;
  }
  std::string error;
  const auto again = ins::task_from_json(ins::task_json(loaded), &error);
  fuzz_check(again.has_value());
  fuzz_check(training::write_task_description(*again) == yaml);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Json::Value body;
  if (!rise::fuzz::parse_json(text, &body)) return 0;
  std::string error;
  const auto task = ins::task_from_json(body, &error);
  if (!task) {
    fuzz_check(!error.empty());
    return 0;
  }
  const ins::TaskCheck check = ins::check_task(*task, kFile);
  fuzz_check(!check.yaml.empty());
  rise::fuzz::check_builder_errors(check.errors, check.yaml, "fuzz_task.yaml");
  json_round_trip(check.yaml);
  return 0;
}
