// `rise demo training`: the example training end to end, as a user runs it.

#include <catch2/catch.hpp>
#include <unistd.h>

#include "process/child_process.hpp"
#include "sim/training/report.hpp"
#include "tests/training/training_files.hpp"

using rise::process::ChildProcess;
using Catch::Matchers::Contains;

TEST_CASE("rise demo training runs the Fig. 10 example end to end and writes the reports", "[training]") {
  const auto dir = rise::test::temp_dir("demo");
  const std::string lcm = "udpm://239.255.76.67:" + std::to_string(8700 + ::getpid() % 300) + "?ttl=0";
  ChildProcess demo({std::string(RISE_BINARY_DIR) + "/bin/rise", "demo", "training", "--id", "demo", "--lcm", lcm,
                     "--out", dir + "/out"},
                    dir + "/demo.log");
  const int rc = demo.wait_for(90000);
  const auto log = rise::test::read_file(dir + "/demo.log");
  INFO(log);
  REQUIRE(rc == 0);
  CHECK_THAT(log, Contains("mission1   attempt 1  approach_object    score   20  success"));
  CHECK_THAT(log, Contains("mission3   attempt 1  metro_transport    score   21  success"));
  CHECK_THAT(log, Contains("total score           41"));
  CHECK_THAT(log, Contains("result                ok"));
  const auto journal = rise::sim::training::read_journal(dir + "/out/journal.jsonl");
  REQUIRE(!journal.empty());
  CHECK(journal.back().type == "training_finished");
  CHECK_THAT(rise::test::read_file(dir + "/out/02_mission3_1.html"), Contains("id=\"trajectory\""));
  CHECK_THAT(rise::test::read_file(dir + "/out/training.html"), Contains("02_mission3_1.html"));

  // The same --out again is refused: its journal belongs to a training already run.
  ChildProcess again({std::string(RISE_BINARY_DIR) + "/bin/rise-trainer", "train",
                      rise::test::src("sim/training/examples/fig10_training.yaml"), "--out", dir + "/out", "--lcm", lcm},
                     dir + "/again.log");
  CHECK(again.wait_for(20000) == 2);
  CHECK_THAT(rise::test::read_file(dir + "/again.log"), Contains("journal.jsonl exists: resume it with --resume"));
}
