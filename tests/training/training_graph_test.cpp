#include <catch2/catch.hpp>

#include "sim/training/training_graph.hpp"
#include "tests/training/training_files.hpp"

using namespace rise::sim::training;
using rise::test::src;
using Catch::Matchers::Contains;

namespace {

TaskResult result(int score, bool success, std::map<std::string, int> counts = {}) {
  TaskResult r;
  r.score = score;
  r.success = success;
  r.finished = true;
  r.counts = std::move(counts);
  return r;
}

// The nodes' names and attempts in the order the walk visited them.
std::vector<std::string> walk(const TrainingGraph& g, const std::vector<TaskResult>& results, TrainingWalker* out = nullptr) {
  TrainingWalker w(g);
  std::vector<std::string> path;
  for (const auto& r : results) {
    const auto cur = w.current();
    if (!cur) break;
    path.push_back(cur->first + "#" + std::to_string(cur->second));
    w.record(r);
  }
  path.push_back(w.ended() ? "END" : w.current()->first + "#" + std::to_string(w.current()->second));
  if (out) *out = w;
  return path;
}

std::string graph_error(const std::string& text, bool load_tasks = false) {
  try {
    parse_training_graph(text, src("sim/training/examples/bad_training.yaml"), load_tasks);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

const std::string kBad = src("sim/training/examples/bad_training.yaml");

}  // namespace

TEST_CASE("the Fig. 10 example training loads, its tasks with it", "[training]") {
  const auto g = load_training_graph(src("sim/training/examples/fig10_training.yaml"));
  CHECK(g.name == "fig10_metro");
  REQUIRE(g.nodes.size() == 3);
  CHECK(g.nodes[0].task->name == "approach_object");
  CHECK(g.nodes[2].task->name == "metro_transport");
  CHECK(g.nodes[2].max_attempts == 2);
  CHECK(g.transitions.size() == 11);
  CHECK(g.transitions[1].condition->text == "score GE 20");
  CHECK(g.transitions[8].condition->field == "score");  // "result" is the score
  CHECK(validate_training_graph(g).empty());
}

TEST_CASE("the training graph follows the right transitions for given results", "[training]") {
  const auto g = load_training_graph(src("sim/training/examples/fig10_training.yaml"));
  SECTION("C3: a full score skips mission 2") {
    CHECK(walk(g, {result(20, true), result(21, true)}) == std::vector<std::string>{"mission1#1", "mission3#1", "END"});
  }
  SECTION("C2 then C4 and the neutralization's event count") {
    CHECK(walk(g, {result(10, true), result(5, false), result(20, true, {{"neutralized", 1}}), result(30, true)}) ==
          std::vector<std::string>{"mission1#1", "mission2#1", "mission2#2", "mission3#1", "END"});
  }
  SECTION("C5 repeats the transport until its attempts run out, then result LT 10 ends") {
    TrainingWalker w(g);
    CHECK(walk(g, {result(25, true), result(5, false), result(9, false)}, &w) ==
          std::vector<std::string>{"mission1#1", "mission3#1", "mission3#2", "END"});
    CHECK(w.visits().at(1).transition == "result LT 10 → mission3");
    CHECK(w.visits().at(2).transition == "result LT 10 → END");
    CHECK(w.end_reason() == "END reached");
    CHECK(w.total_score() == 39);
    CHECK(w.attempts("mission3") == 2);
  }
  SECTION("C1 repeats mission 1, then the training ends when its attempts are used up") {
    CHECK(walk(g, {result(0, false), result(3, false)}) == std::vector<std::string>{"mission1#1", "mission1#2", "END"});
  }
  SECTION("replaying the same results gives the same walk (resume)") {
    const std::vector<TaskResult> rs{result(10, true), result(20, true, {{"neutralized", 1}})};
    TrainingWalker a(g), b(g);
    walk(g, rs, &a);
    walk(g, rs, &b);
    CHECK(a.current() == b.current());
    CHECK(a.current()->first == "mission3");
  }
}

TEST_CASE("conditions compare a result field with LT, LE, GT, GE, EQ and NE", "[training]") {
  const auto [text, holds] = GENERATE(table<std::string, bool>({
      {"score LT 10", true}, {"score LT 9", false}, {"score LE 9", true}, {"score GT 8", true}, {"score GT 9", false},
      {"score GE 9", true}, {"score EQ 9", true}, {"score NE 9", false}, {"result LT 10", true},
      {"time_s GE 12.5", true}, {"success EQ 1", true}, {"success EQ false", false}, {"events.hit GE 2", true},
      {"events.miss EQ 0", false},  // an unknown event is no field: no condition on it holds
  }));
  TaskResult r = result(9, true, {{"hit", 2}});
  r.time_s = 12.5;
  CAPTURE(text);
  CHECK(parse_condition(text).holds(r) == holds);
}

TEST_CASE("invalid training graphs are refused with a message naming file and line", "[training]") {
  const std::string head = "training: bad\nnodes:\n  - {name: a, task: metro_transport.yaml}\n  - {name: b, task: approach_object.yaml}\n";
  SECTION("a transition to an unknown node") {
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: START, to: a}\n  - {from: a, to: c}\n  - {from: a, to: b}\n  - {from: b, to: END}\n"),
               Contains(kBad + ":7: transition to 'c': unknown node"));
  }
  SECTION("an unreachable node") {
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: START, to: a}\n  - {from: a, to: END}\n  - {from: b, to: END}\n"),
               Contains(kBad + ":4: node 'b' is unreachable from START"));
  }
  SECTION("a node with no path to END") {
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: START, to: a}\n  - {from: a, to: END, if: score GE 1}\n  - {from: a, to: b}\n"),
               Contains(kBad + ":4: node 'b' has no path to END"));
  }
  SECTION("a loop with no exit") {
    const auto e = graph_error(head + "transitions:\n  - {from: START, to: a}\n  - {from: a, to: b, if: score LT 5}\n  - {from: b, to: a}\n  - {from: a, to: b}\n");
    CHECK_THAT(e, Contains(kBad + ":3: loop a → b → a has no exit"));
    CHECK_THAT(e, !Contains("no path to END"));
  }
  SECTION("a self-loop with no exit") {
    CHECK_THAT(graph_error("training: bad\nnodes:\n  - {name: a, task: x.yaml}\ntransitions:\n  - {from: START, to: a}\n  - {from: a, to: a}\n"),
               Contains(kBad + ":3: loop a → a has no exit"));
  }
  SECTION("a node whose task is empty (the fuzzer's `task: !b.yaml`, a tag without a value)") {
    CHECK_THAT(graph_error("training: bad\nnodes:\n  - {name: a, task: !b.yaml}\ntransitions:\n  - {from: START, to: a}\n"
                           "  - {from: a, to: END}\n"),
               Contains(kBad + ":3: nodes[0].task: must name a task file"));
  }
  SECTION("nothing leaves START") {
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: a, to: b}\n  - {from: b, to: END}\n"),
               Contains(kBad + ":1: no transition from START"));
  }
  SECTION("a condition on START") {
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: START, to: a, if: score GT 1}\n  - {from: a, to: b}\n  - {from: b, to: END}\n"),
               Contains(kBad + ":6: transition from START: no condition allowed"));
  }
  SECTION("a bad condition") {
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: START, to: a}\n  - {from: a, to: END, if: score ABOUT 3}\n"),
               Contains(kBad + ":7: transitions[1].if: condition 'score ABOUT 3': unknown comparison 'ABOUT'"));
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: START, to: a}\n  - {from: a, to: END, if: points LT 3}\n"),
               Contains(kBad + ":7: transitions[1].if: condition 'points LT 3': unknown field 'points'"));
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: START, to: a}\n  - {from: a, to: END, if: score LT ten}\n"),
               Contains("'ten' is not a number"));
  }
  SECTION("a condition on an event the node's task lacks") {
    CHECK_THAT(graph_error(head + "transitions:\n  - {from: START, to: a}\n  - {from: a, to: b, if: events.exploded GE 1}\n  - {from: a, to: b}\n  - {from: b, to: END}\n", true),
               Contains(kBad + ":7: condition 'events.exploded GE 1': task metro_transport"));
  }
  SECTION("a duplicate node and a bad attempt count") {
    CHECK_THAT(graph_error("training: bad\nnodes:\n  - {name: a, task: x.yaml}\n  - {name: a, task: y.yaml}\ntransitions: []\n"),
               Contains(kBad + ":4: nodes[1].name: duplicate node 'a'"));
    CHECK_THAT(graph_error("training: bad\nnodes:\n  - {name: a, task: x.yaml, max_attempts: 0}\ntransitions: []\n"),
               Contains(kBad + ":3: nodes[0].max_attempts: must be >= 1"));
  }
  SECTION("every error at once, one per line") {
    const auto e = graph_error(head + "transitions:\n  - {from: a, to: c}\n");
    CHECK_THAT(e, Contains("no transition from START"));
    CHECK_THAT(e, Contains("transition to 'c': unknown node"));
    CHECK_THAT(e, Contains("node 'a' is unreachable from START"));
    CHECK_THAT(e, Contains("node 'b' is unreachable from START"));
  }
}

// Found by the training_graph fuzz target: a key holding a control character
// and a line break ("trai\x06\x00ng") split its "file:line: key: unknown key"
// error over two lines. Control characters are written as \xNN.
TEST_CASE("an error naming a key with control characters stays on one line", "[training]") {
  const std::string error = graph_error(std::string("trai\x06\x00ng: t\n", 12));
  INFO(error);
  CHECK(error.find('\n') == std::string::npos);
  CHECK(error.find("\\x06") != std::string::npos);
}

// Found by the training_graph fuzz target (bench/fuzz_all's second run): a
// node name with a line break ("mission1\n2") split a validation error.
TEST_CASE("validation errors naming a node with a line break stay one per line", "[training]") {
  const std::string error = graph_error(
      "training: t\nnodes:\n  - {name: \"a\\nb\", task: a.yaml}\ntransitions:\n  - {from: START, to: \"c\\nd\"}\n");
  INFO(error);
  for (std::size_t begin = 0; begin < error.size();) {
    const std::size_t end = std::min(error.find('\n', begin), error.size());
    CHECK(error.compare(begin, kBad.size(), kBad) == 0);
    begin = end + 1;
  }
  CHECK(error.find("c\\x0ad") != std::string::npos);
}
