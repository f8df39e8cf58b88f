// The training YAML writer (the Training Builder saves through it): load →
// write → load gives the same graph, and the same walk, for every shipped
// training file and for names, titles and comments that need quoting.

#include <catch2/catch.hpp>

#include <filesystem>
#include <regex>

#include "panels/yaml_reader.hpp"
#include "sim/training/training_graph.hpp"
#include "sim/training/training_writer.hpp"
#include "tests/training/training_files.hpp"

using namespace rise::sim::training;
using rise::test::src;
namespace fs = std::filesystem;

namespace {

// What a graph means: its names, tasks, attempts, transitions in order with
// their conditions, and the comments; not the lines they sit on.
void check_same_graph(const TrainingGraph& a, const TrainingGraph& b) {
  CHECK(a.name == b.name);
  CHECK(a.title == b.title);
  CHECK(a.comment == b.comment);
  REQUIRE(a.nodes.size() == b.nodes.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i) {
    INFO("node " << a.nodes[i].name);
    CHECK(a.nodes[i].name == b.nodes[i].name);
    CHECK(a.nodes[i].task_file == b.nodes[i].task_file);
    CHECK(a.nodes[i].task_path == b.nodes[i].task_path);
    CHECK(a.nodes[i].max_attempts == b.nodes[i].max_attempts);
    CHECK(a.nodes[i].comment == b.nodes[i].comment);
  }
  REQUIRE(a.transitions.size() == b.transitions.size());
  for (std::size_t i = 0; i < a.transitions.size(); ++i) {
    const auto &x = a.transitions[i], &y = b.transitions[i];
    INFO("transition " << i << ": " << x.from << " → " << x.to);
    CHECK(x.from == y.from);
    CHECK(x.to == y.to);
    CHECK(x.comment == y.comment);
    REQUIRE(x.condition.has_value() == y.condition.has_value());
    if (!x.condition) continue;
    CHECK(x.condition->text == y.condition->text);
    CHECK(x.condition->field == y.condition->field);
    CHECK(x.condition->op == y.condition->op);
    CHECK(x.condition->value == y.condition->value);
  }
}

// The nodes a walk visits when every task ends with `score` (and success when score > 0).
std::vector<std::string> walk(const TrainingGraph& g, const std::vector<int>& scores) {
  TrainingWalker w(g);
  std::vector<std::string> path;
  for (int s : scores) {
    if (w.ended()) break;
    path.push_back(w.current()->first);
    TaskResult r;
    r.score = s;
    r.success = s > 0;
    r.finished = true;
    w.record(r);
  }
  path.push_back(w.ended() ? w.end_reason() : "...");
  return path;
}

std::vector<std::string> shipped_trainings() {
  std::vector<std::string> out;
  static const std::regex training_key("(^|\n)training:");
  for (const auto& e : fs::directory_iterator(src("sim/training/examples")))
    if (e.path().extension() == ".yaml" &&
        std::regex_search(rise::panels::read_text_file(e.path().string()), training_key))
      out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("every shipped training file keeps its meaning through write and load", "[training]") {
  const auto files = shipped_trainings();
  REQUIRE(!files.empty());
  for (const auto& file : files) {
    INFO(file);
    const TrainingGraph original = load_training_graph(file);
    TrainingYamlLines lines;
    const std::string text = write_training_graph(original, &lines);
    // Written beside the original, so its task paths resolve the same.
    const TrainingGraph again = parse_training_graph(text, file);
    check_same_graph(original, again);
    CHECK(write_training_graph(again) == text);  // a fixed point
    for (std::size_t i = 0; i < again.nodes.size(); ++i) CHECK(again.nodes[i].line == lines.nodes[i]);
    for (std::size_t i = 0; i < again.transitions.size(); ++i) CHECK(again.transitions[i].line == lines.transitions[i]);
    for (const auto& scores : std::vector<std::vector<int>>{{0, 0, 0, 0}, {25, 5, 5}, {10, 0, 12}, {10, 5, 30}})
      CHECK(walk(original, scores) == walk(again, scores));
  }
}

TEST_CASE("the Fig. 10 training's comments survive a save", "[training]") {
  const auto g = load_training_graph(src("sim/training/examples/fig10_training.yaml"));
  CHECK(g.comment.rfind("The seed paper's Fig. 10 training graph", 0) == 0);
  CHECK(g.transitions[1].comment == "C3: Mission 2 not needed");
  CHECK(g.transitions[3].comment == "C1: repeat");
  CHECK(g.transitions[0].comment.empty());
  const std::string text = write_training_graph(g);
  CHECK(text.find("  - {from: mission1, if: \"score GE 20\", to: mission3}") != std::string::npos);
  CHECK(text.find("# C3: Mission 2 not needed\n") != std::string::npos);
  CHECK(text.find("  - {name: mission1, task: approach_object.yaml, max_attempts: 2}") != std::string::npos);
}

TEST_CASE("names, titles and comments that need quoting read back as written", "[training]") {
  TrainingGraph g;
  g.name = "drill: \"night\" #2";
  g.title = "Übung — quotes \" and \\ and a\ttab";
  g.comment = "first line\n\nthird: with # and 'quotes'";
  TrainingNode n;
  n.name = "yes";  // YAML 1.1 would read a plain yes as a boolean
  n.task_path = "../examples/approach_object.yaml";
  n.task_file = src("sim/training/examples/approach_object.yaml");
  n.max_attempts = 4;
  n.comment = "a # in a comment\nand a second line";
  g.nodes.push_back(n);
  Transition t1{"START", "yes", std::nullopt, 0, "start here"};
  Transition t2{"yes", "END", parse_condition("events.near_object GE 1"), 0, ""};
  Transition t3{"yes", "yes", std::nullopt, 0, "'repeat' \"it\""};
  g.transitions = {t1, t2, t3};
  const std::string file = src("sim/training/examples/quoted.yaml");
  const std::string text = write_training_graph(g);
  INFO(text);
  TrainingGraph again = parse_training_graph(text, file);
  CHECK(again.name == g.name);
  CHECK(again.title == g.title);
  CHECK(again.comment == g.comment);
  CHECK(again.nodes[0].name == "yes");
  CHECK(again.nodes[0].task_file == n.task_file);
  CHECK(again.nodes[0].comment == "a # in a comment and a second line");
  CHECK(again.transitions[0].comment == "start here");
  CHECK(again.transitions[1].condition->field == "events.near_object");
  CHECK(again.transitions[2].comment == "'repeat' \"it\"");
  CHECK(yaml_scalar("approach_object.yaml") == "approach_object.yaml");
  CHECK(yaml_scalar("a\nb") == "\"a\\nb\"");
}

TEST_CASE("a file's opening comment whose last line is blank reads as the writer gives it back (fuzz_training_graph)",
          "[training]") {
  const std::string text = std::string("# head\n# \x01\x04\n#\ntraining: t\nnodes:\n  - {name: a, task: x.yaml}\n") +
                           "transitions:\n  - {from: START, to: a}\n  - {from: a, to: END}\n";
  const TrainingGraph g = parse_training_graph(text, src("sim/training/examples/blank.yaml"), false);
  CHECK(g.comment == "head");
  const std::string written = write_training_graph(g);
  INFO(written);
  CHECK(parse_training_graph(written, src("sim/training/examples/blank.yaml"), false).comment == "head");
  CHECK(write_training_graph(parse_training_graph(written, src("sim/training/examples/blank.yaml"), false)) == written);
  // Blank lines first or last in a comment the page sent (fuzz_task_builder): written without them.
  TrainingGraph h = g;
  h.comment = "\n\nhead\n\nbody\n\n";
  const std::string blank_ends = write_training_graph(h);
  INFO(blank_ends);
  CHECK(blank_ends.rfind("# head\n#\n# body\ntraining: t\n", 0) == 0);
  CHECK(parse_training_graph(blank_ends, src("sim/training/examples/blank.yaml"), false).comment == "head\n\nbody");
}

TEST_CASE("a condition that does not parse is written as it is, for the loader to name with line and key", "[training]") {
  auto g = load_training_graph(src("sim/training/examples/fig10_training.yaml"), false);
  Condition bad;
  bad.text = "score GE lots";
  g.transitions[1].condition = bad;
  TrainingYamlLines lines;
  const std::string text = write_training_graph(g, &lines);
  try {
    parse_training_graph(text, "drill.yaml", false);
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()) == "drill.yaml:" + std::to_string(lines.transitions[1]) +
                                       ": transitions[1].if: condition 'score GE lots': 'lots' is not a number");
  }
}
