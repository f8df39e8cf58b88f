#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>
#include <string>

#include "semantic/app/progress_bar.hpp"

using namespace rise::semantic;

namespace {
std::string contents(std::FILE* f) {
  std::rewind(f);
  std::string s;
  char buffer[256];
  while (std::fgets(buffer, sizeof buffer, f) != nullptr) s += buffer;
  return s;
}
}  // namespace

TEST_CASE("the progress line fills its bar in proportion and clamps what is past the end", "[semantic]") {
  CHECK(progress_line(0, 4, "icp", 8) == "icp                [........]   0%  0/4");
  CHECK(progress_line(1, 4, "icp", 8) == "icp                [##......]  25%  1/4");
  CHECK(progress_line(9, 4, "icp", 8) == "icp                [########] 100%  4/4");
  CHECK(progress_line(0, 0, "map", 4) == "map                [....]   0%  0/0");
}

TEST_CASE("off a terminal the progress bar writes one line per stage", "[semantic]") {
  std::FILE* f = std::tmpfile();
  REQUIRE(f != nullptr);
  {
    ProgressBar bar(f);  // a file is no terminal
    const auto report = bar.callback();
    for (std::size_t i = 0; i <= 5; ++i) report(i, 5, "sequential icp");
    report(0, 1, "relaxation");
    report(1, 1, "relaxation");
  }
  const std::string text = contents(f);
  std::fclose(f);
  INFO(text);
  CHECK(text.find("sequential icp: 5/5") == 0);
  const auto second = text.find("\nrelaxation: 1/1");
  CHECK(second != std::string::npos);
  CHECK(std::count(text.begin(), text.end(), '\n') == 2);
  CHECK(text.find('\r') == std::string::npos);
}

TEST_CASE("on a terminal the progress bar redraws its line in place", "[semantic]") {
  std::FILE* f = std::tmpfile();
  REQUIRE(f != nullptr);
  {
    ProgressBar bar(f, true);
    for (std::size_t i = 0; i <= 4; ++i) bar.update(i, 4, "loops");
  }
  const std::string text = contents(f);
  std::fclose(f);
  CHECK(std::count(text.begin(), text.end(), '\r') == 6);  // 0, 25, 50, 75, 100 % and the final line
  CHECK(std::count(text.begin(), text.end(), '\n') == 1);
  CHECK(text.find("100%  4/4") != std::string::npos);
}
