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
#include "tests/fuzz/fuzz_check.hpp"

namespace ins = rise::instructor;
namespace training = rise::sim::training;

namespace {

// Beside the shipped task files, so that ../../worlds/building.yaml resolves.
const std::string kFile = std::string(RISE_SOURCE_DIR) + "/sim/training/examples/fuzz_task.yaml";

int line_count(const std::string& text) {
  int n = 0;
  for (const char c : text) n += c == '\n';
  return n;
}

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
  std::string parse_error;
  const std::unique_ptr<Json::CharReader> reader(Json::CharReaderBuilder().newCharReader());
  if (!reader->parse(text.data(), text.data() + text.size(), &body, &parse_error)) return 0;
  std::string error;
  const auto task = ins::task_from_json(body, &error);
  if (!task) {
    fuzz_check(!error.empty());
    return 0;
  }
  const ins::TaskCheck check = ins::check_task(*task, kFile);
  fuzz_check(!check.yaml.empty());
  for (const auto& e : check.errors) {
    fuzz_check(!e.message.empty());
    if (e.file == "fuzz_task.yaml") fuzz_check(e.line >= 0 && e.line <= line_count(check.yaml) + 1);
  }
  json_round_trip(check.yaml);
  return 0;
}
