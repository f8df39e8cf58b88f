// libFuzzer target: the Training Builder's request body (the page's graph as
// JSON, instructor/training_builder.hpp), without a server: read, written as
// YAML and checked by the trainer's loader against the shipped task files.
// None may throw; every error has a message, and one in the training names a
// line of the YAML it was given; a YAML that loads goes through the page's
// JSON and back to the same text (what the page sends back unchanged saves
// unchanged).
#include <json/json.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "instructor/training_builder.hpp"
#include "sim/training/training_writer.hpp"
#include "tests/fuzz/builder_fuzz.hpp"

namespace ins = rise::instructor;
namespace training = rise::sim::training;

namespace {

// Beside the shipped task files, so that a graph naming them loads them.
const std::string kFile = std::string(RISE_SOURCE_DIR) + "/sim/training/examples/fuzz_training.yaml";

void json_round_trip(const std::string& yaml) {
  training::TrainingGraph loaded;
  try {
    loaded = training::parse_training_graph(yaml, kFile, false);
  } catch (const std::exception&) {
    return;
  }
  std::string error;
  const auto again = ins::training_graph_from_json(ins::training_graph_json(loaded), &error);
  fuzz_check(again.has_value());
  fuzz_check(training::write_training_graph(*again) == yaml);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Json::Value body;
  if (!rise::fuzz::parse_json(text, &body)) return 0;
  std::string error;
  const auto graph = ins::training_graph_from_json(body, &error);
  if (!graph) {
    fuzz_check(!error.empty());
    return 0;
  }
  const ins::TrainingCheck check = ins::check_training(*graph, kFile);
  fuzz_check(!check.yaml.empty());
  rise::fuzz::check_builder_errors(check.errors, check.yaml, "fuzz_training.yaml");
  json_round_trip(check.yaml);
  return 0;
}
