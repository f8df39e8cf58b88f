// The Robot Builder's save: a robot file's scalars edited in place in its
// text (sim/yaml_edit.hpp). Round trip over every shipped robot: rewriting
// every value as it is changes no byte and the loader reads the same robot;
// changing one value changes that one field of the loaded robot and one line
// of the text, every comment kept.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "sim/robot_description.hpp"
#include "sim/yaml_edit.hpp"

using namespace rise::sim;
namespace fs = std::filesystem;

namespace {

const std::string kRobots = std::string(RISE_SOURCE_DIR) + "/sim/robots/";

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> shipped_robots() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(kRobots))
    if (e.path().extension() == ".yaml") out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// The comments of a text: each "# ..." to the end of its line.
std::multiset<std::string> comments(const std::string& text) {
  std::multiset<std::string> out;
  for (const auto& l : lines_of(text)) {
    const auto at = l.find('#');
    if (at != std::string::npos) out.insert(l.substr(at));
  }
  return out;
}

int lines_changed(const std::string& a, const std::string& b) {
  const auto la = lines_of(a), lb = lines_of(b);
  if (la.size() != lb.size()) return -1;
  int n = 0;
  for (std::size_t i = 0; i < la.size(); ++i) n += la[i] != lb[i];
  return n;
}

// A motor limit each shipped robot has, its new value, and the field it sets.
struct LimitEdit {
  std::string path;
  std::string value;
  std::function<void(RobotDescription&)> expect;
};

LimitEdit limit_edit_for(const RobotDescription& d) {
  if (d.kind == RobotKind::UrdfTree)
    return {"control.joints." + d.control.joints[0].joint + ".max", "3.5",
            [](RobotDescription& r) { r.control.joints[0].axis.max = 3.5; }};
  return {"control.linear.max_mps", "0.3", [](RobotDescription& r) { r.control.linear.max = 0.3; }};
}

}  // namespace

TEST_CASE("every shipped robot: rewriting every value as it is keeps the bytes and the robot", "[sim][yaml_edit]") {
  const auto robots = shipped_robots();
  REQUIRE(robots.size() >= 3);
  for (const auto& path : robots) {
    INFO(path);
    const std::string text = slurp(path);
    const RobotDescription before = parse_robot_description(text, path);
    std::vector<YamlEdit> edits;
    for (const auto& s : yaml_scalars(text)) edits.push_back({s.path, s.value});
    REQUIRE(edits.size() > 20);
    const std::string saved = apply_yaml_edits(text, edits);
    CHECK(saved == text);
    CHECK(parse_robot_description(saved, path) == before);
  }
}

TEST_CASE("every shipped robot: a changed motor limit changes that field and one line, comments kept", "[sim][yaml_edit]") {
  for (const auto& path : shipped_robots()) {
    INFO(path);
    const std::string text = slurp(path);
    const RobotDescription before = parse_robot_description(text, path);
    const LimitEdit edit = limit_edit_for(before);
    const std::string saved = apply_yaml_edits(text, {{edit.path, edit.value}});
    CHECK(lines_changed(text, saved) == 1);
    CHECK(comments(saved) == comments(text));
    RobotDescription expected = before;
    edit.expect(expected);
    const RobotDescription after = parse_robot_description(saved, path);
    CHECK(after == expected);
    CHECK_FALSE(after == before);
    // Saved again with the old value: the file as shipped.
    std::string old_value;
    for (const auto& s : yaml_scalars(text))
      if (s.path == edit.path) old_value = s.value;
    CHECK(apply_yaml_edits(saved, {{edit.path, old_value}}) == text);
  }
}

TEST_CASE("a key the file lacks is added to its flow or block mapping", "[sim][yaml_edit]") {
  const std::string path = kRobots + "skid4.yaml";
  const std::string text = slurp(path);
  // control.linear is a flow mapping without invert.
  const std::string saved = apply_yaml_edits(text, {{"control.linear.invert", "true"}, {"sounds.horn.pitch", "1.5"}});
  CHECK(saved.find("linear:  {axis: drive_y, max_mps: 1.2, invert: true}") != std::string::npos);
  CHECK(comments(saved) == comments(text));
  const RobotDescription d = parse_robot_description(saved, path);
  CHECK(d.control.linear.invert);
  CHECK(d.sounds.back().pitch == 1.5);

  const std::string block = "# head\na:\n  b: 1   # one\n  c:\n    d: 2\n";
  CHECK(apply_yaml_edits(block, {{"a.e", "3"}}) == "# head\na:\n  e: 3\n  b: 1   # one\n  c:\n    d: 2\n");
  CHECK(apply_yaml_edits(block, {{"a.c.f.g", "x y"}}) == "# head\na:\n  b: 1   # one\n  c:\n    f: {g: \"x y\"}\n    d: 2\n");
  CHECK(apply_yaml_edits("a: {}\n", {{"a.b", "1"}}) == "a: {b: 1}\n");
}

TEST_CASE("values are written so that they read back as given", "[sim][yaml_edit]") {
  const std::string text = "a: {b: 'x', c: \"y\\\"z\", d: 1}  # keep\nl: [1, 2, 3]\n";
  for (const std::string v : {"plain", "two words", "a,b", "{x}", "#", "\"q\"", "", "-1.5e3", "tab\there", "ü"}) {
    INFO(v);
    for (const std::string p : {"a.b", "a.c", "a.d", "l[1]", "a.new"}) {
      const std::string out = apply_yaml_edits(text, {{p, v}});
      std::string got;
      for (const auto& s : yaml_scalars(out))
        if (s.path == p) got = s.value;
      CHECK(got == v);
      CHECK(out.find("# keep") != std::string::npos);
    }
  }
  CHECK(yaml_flow_scalar("0.3") == "0.3");
  CHECK(yaml_flow_scalar("drive_y") == "drive_y");
  CHECK(yaml_flow_scalar("a b") == "\"a b\"");
}

TEST_CASE("an edit that cannot apply names its path and changes nothing", "[sim][yaml_edit]") {
  const std::string text = slurp(kRobots + "tracked_eod.yaml");
  const auto fails = [&](const std::string& path, const std::string& what) {
    INFO(path);
    try {
      apply_yaml_edits(text, {{"control.linear.max_mps", "0.5"}, {path, "1"}});
      FAIL("no error");
    } catch (const YamlEditError& e) {
      CHECK(e.path() == path);
      CHECK_THAT(e.what(), Catch::Contains(what));
    }
  };
  fails("control.linear.max_mps.x", "not a mapping");
  fails("control.speed_scale.values[7]", "the list has 3 items");
  fails("control.arm", "not a value");
  fails("control..x", "expected a key");
  fails("control.", "ends in '.'");
  fails("a/b", "expected '.' or '['");
  fails("sensors.cameras[0].extra[1]", "a list that is not there");
  fails("", "expected a path");
  CHECK_THROWS_AS(yaml_scalars("a: [1, 2"), std::runtime_error);
}

TEST_CASE("YAML an edit in place cannot change alone is refused, not changed otherwise", "[sim][yaml_edit]") {
  // An anchored value is also its aliases' value; a block scalar spans lines.
  for (const auto& [text, path] : std::vector<std::pair<std::string, std::string>>{
           {"a: &x 1\nb: *x\n", "a"}, {"a: &x 1\nb: *x\n", "b"}, {"a: |\n  two\n  lines\n", "a"},
           {"a: plain\n  continued\n", "a"}, {"- x: 1\n  y: 2\n", "[0].z"}}) {
    INFO(text << " " << path);
    CHECK_THROWS_AS(apply_yaml_edits(text, {{path, "9"}}), YamlEditError);
  }
  CHECK(apply_yaml_edits("a: {b: 1, }\n", {{"a.c", "2"}}) == "a: {b: 1, c: 2 }\n");
  CHECK(apply_yaml_edits("a: {b: 1  # one\n   }\n", {{"a.c", "2"}}) == "a: {b: 1, c: 2  # one\n   }\n");
}

TEST_CASE("the paths are the loader's keys", "[sim][yaml_edit]") {
  // An error of the loader names the key the page edits (control.linear.max_mps).
  const std::string path = kRobots + "skid4.yaml";
  const std::string saved = apply_yaml_edits(slurp(path), {{"control.linear.max_mps", "-1"}});
  try {
    parse_robot_description(saved, path);
    FAIL("loaded");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(e.what(), Catch::Contains(":12: control.linear.max_mps:"));
  }
}
