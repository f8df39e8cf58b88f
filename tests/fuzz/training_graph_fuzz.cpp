// libFuzzer target: the training graph YAML (sim/training/training_graph.hpp),
// parsed without its task files (they are other files: fuzz_configs reads
// tasks). An error must be a std::runtime_error whose every line starts with
// the file name ("file:line: ..."). A graph that loads is valid, so: giving
// each node a task with one event leaves only "has no event" errors; and a
// walk of it, fed results from the first byte, stays on its nodes within
// their max_attempts and ends after at most the sum of them. Written again
// (sim/training/training_writer.hpp, what the Training Builder saves) it
// loads as the same graph, comments included, and writes the same text.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "sim/training/training_graph.hpp"
#include "sim/training/training_writer.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace training = rise::sim::training;

namespace {

const std::string kFile = "fuzz/training.yaml";

// Every line of an error names the file.
void check_lines(std::string_view what) {
  for (std::size_t begin = 0; begin < what.size();) {
    std::size_t end = what.find('\n', begin);
    if (end == std::string_view::npos) end = what.size();
    fuzz_check(what.substr(begin, end - begin).starts_with(kFile));
    begin = end + 1;
  }
}

// With a task of one event ("neutralized") on every node, the only new
// errors are conditions on other events.
void check_events(training::TrainingGraph g) {
  for (auto& n : g.nodes) {
    training::TaskDescription t;
    t.name = n.name;
    t.file = n.task_file;
    t.events.push_back({});
    t.events.back().name = "neutralized";
    n.task = std::move(t);
  }
  for (const auto& e : training::validate_training_graph(g)) {
    fuzz_check(e.starts_with(kFile));
    fuzz_check(e.find("has no event") != std::string::npos);
  }
}

// A result for the walk's step `step`, from `k`.
training::TaskResult result_of(unsigned k, int step) {
  training::TaskResult r;
  r.score = static_cast<int>((k * 37u + static_cast<unsigned>(step) * 11u) % 41u) - 5;
  r.success = ((k >> (step % 8)) & 1u) != 0;
  r.time_s = (k + static_cast<unsigned>(step)) % 300u;
  r.counts["neutralized"] = static_cast<int>((k >> 4) & 1u);
  return r;
}

void walk(const training::TrainingGraph& g, unsigned k) {
  long long budget = 0;
  for (const auto& n : g.nodes) {
    fuzz_check(n.max_attempts >= 1);
    budget += n.max_attempts;
  }
  const long long steps = std::min(budget, 2000LL);
  training::TrainingWalker w(g);
  for (long long i = 0; i < steps && !w.ended(); ++i) {
    const auto current = w.current();
    fuzz_check(current.has_value());
    const training::TrainingNode* n = g.node(current->first);
    fuzz_check(n != nullptr);
    fuzz_check(current->second >= 1 && current->second <= n->max_attempts);
    w.record(result_of(k, static_cast<int>(i)));
  }
  if (budget <= 2000) fuzz_check(w.ended() && !w.end_reason().empty());
  fuzz_check(static_cast<long long>(w.visits().size()) <= budget);
}

// write → parse gives the same graph; a second write the same text.
void round_trip(const training::TrainingGraph& g) {
  const std::string text = training::write_training_graph(g);
  training::TrainingGraph again;
  try {
    again = training::parse_training_graph(text, kFile, false);
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "written graph does not load: %s\n%s", e.what(), text.c_str());
    fuzz_check(false);
  }
  fuzz_check(again.name == g.name && again.title == g.title && again.comment == g.comment);
  fuzz_check(again.nodes.size() == g.nodes.size() && again.transitions.size() == g.transitions.size());
  for (std::size_t i = 0; i < g.nodes.size(); ++i) {
    const auto &a = g.nodes[i], &b = again.nodes[i];
    fuzz_check(a.name == b.name && a.task_path == b.task_path && a.task_file == b.task_file);
    fuzz_check(a.max_attempts == b.max_attempts && a.comment == b.comment);
  }
  for (std::size_t i = 0; i < g.transitions.size(); ++i) {
    const auto &a = g.transitions[i], &b = again.transitions[i];
    fuzz_check(a.from == b.from && a.to == b.to && a.comment == b.comment);
    fuzz_check(a.condition.has_value() == b.condition.has_value());
    if (a.condition) fuzz_check(a.condition->text == b.condition->text && a.condition->op == b.condition->op);
  }
  fuzz_check(training::write_training_graph(again) == text);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  training::TrainingGraph g;
  try {
    g = training::parse_training_graph(text, kFile, false);
  } catch (const std::runtime_error& e) {
    check_lines(e.what());
    return 0;
  }
  fuzz_check(!g.nodes.empty() && !g.transitions.empty());
  fuzz_check(training::validate_training_graph(g).empty());
  check_events(g);
  round_trip(g);
  walk(g, data[0]);
  return 0;
}
