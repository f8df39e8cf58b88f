// The builders' file API and the Training Builder's endpoints, in this
// process over real HTTP: a designs folder's files listed and read with their
// version, a proposed graph checked by the trainer's loader (errors with line
// and key), saved atomically, refused with 409 when the file changed on disk
// since it was read, 422 when it would not load, and nothing outside the folder.

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "instructor/design_files.hpp"
#include "instructor/training_builder.hpp"
#include "instructor/web_server.hpp"
#include "sim/training/training_graph.hpp"
#include "builder_api_support.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;
using rise::instructor::DesignFolder;
using rise::instructor::SaveStatus;

namespace {
struct BuilderFixture : BuilderApiFixture {
  BuilderFixture() : BuilderApiFixture("builder-api", "tok-builder") {
    settings.designs_dir = copy_shipped("sim/training/examples", "designs", ".yaml");
  }
  fs::path training() const { return dir / "designs" / "fig10_training.yaml"; }
};

// POST body {version, graph}.
std::string save_body(const Json::Value& graph, const std::string& version) {
  Json::Value b;
  b["graph"] = graph;
  b["version"] = version;
  return text(b);
}
}  // namespace

TEST_CASE("a design's version changes with its bytes and saving checks it", "[instructor][builder]") {
  BuilderFixture f;
  DesignFolder folder(f.settings.designs_dir);
  CHECK(rise::instructor::content_version("") == "cbf29ce484222325");  // FNV-1a 64 of nothing
  CHECK(rise::instructor::content_version("a") != rise::instructor::content_version("b"));
  CHECK(rise::instructor::valid_design_name("fig10_training.yaml", ".yaml"));
  for (const char* bad : {"../x.yaml", ".hidden.yaml", "a/b.yaml", "x.yml", ".yaml", "a b.yaml"})
    CHECK_FALSE(rise::instructor::valid_design_name(bad, ".yaml"));
  const auto listed = folder.list(".yaml");
  CHECK(std::find(listed.begin(), listed.end(), "fig10_training.yaml") != listed.end());
  const auto read = folder.read("fig10_training.yaml");
  CHECK(read.version == rise::instructor::content_version(slurp(f.training())));
  SECTION("a save at the version read writes and gives the new version") {
    const auto out = folder.save("fig10_training.yaml", "x: 1\n", read.version);
    CHECK(out.status == SaveStatus::Saved);
    CHECK(out.version == rise::instructor::content_version("x: 1\n"));
    CHECK(slurp(f.training()) == "x: 1\n");
    // No temporary left beside it.
    for (const auto& e : fs::directory_iterator(f.dir / "designs"))
      CHECK(e.path().filename().string().find(".tmp.") == std::string::npos);
  }
  SECTION("a file changed on disk since it was read is not overwritten") {
    std::ofstream(f.training(), std::ios::app) << "# someone else\n";
    const std::string theirs = slurp(f.training());
    const auto out = folder.save("fig10_training.yaml", "x: 1\n", read.version);
    CHECK(out.status == SaveStatus::Conflict);
    CHECK(out.version == rise::instructor::content_version(theirs));
    CHECK(slurp(f.training()) == theirs);
  }
  SECTION("a link stays a link to the file it names, and the file keeps its permissions") {
    fs::create_directories(f.dir / "elsewhere");
    std::ofstream(f.dir / "elsewhere" / "real.yaml") << "x: 0\n";
    fs::permissions(f.dir / "elsewhere" / "real.yaml", fs::perms::owner_read | fs::perms::owner_write |
                                                           fs::perms::group_read | fs::perms::group_write);
    fs::create_symlink(f.dir / "elsewhere" / "real.yaml", f.dir / "designs" / "linked.yaml");
    const auto v = folder.read("linked.yaml").version;
    REQUIRE(folder.save("linked.yaml", "x: 1\n", v).status == SaveStatus::Saved);
    CHECK(fs::is_symlink(f.dir / "designs" / "linked.yaml"));
    CHECK(slurp(f.dir / "elsewhere" / "real.yaml") == "x: 1\n");
    CHECK((fs::status(f.dir / "elsewhere" / "real.yaml").permissions() & fs::perms::group_write) != fs::perms::none);
  }
  SECTION("a new file is saved with the empty version, and only then") {
    CHECK(folder.save("new.yaml", "x: 1\n", "").status == SaveStatus::Saved);
    CHECK(folder.save("new.yaml", "x: 2\n", "").status == SaveStatus::Conflict);
    CHECK(slurp(f.dir / "designs" / "new.yaml") == "x: 1\n");
  }
}

TEST_CASE("the page's graph JSON of the wrong shape is named, never thrown", "[instructor][builder]") {
  std::string error;
  const auto graph = [&](const std::string& json) {
    error.clear();
    return rise::instructor::training_graph_from_json(parse_json(json), &error);
  };
  CHECK_FALSE(graph("[]"));
  CHECK_FALSE(graph(R"({"training": "t", "nodes": {}, "transitions": []})"));
  CHECK(error == "nodes: expected a list (at most 500)");
  CHECK_FALSE(graph(R"({"training": "t", "nodes": [{"name": "a", "task": "x.yaml", "max_attempts": 1.5}], "transitions": []})"));
  CHECK(error == "nodes[0].max_attempts: expected a whole number");
  CHECK_FALSE(graph(R"({"training": "t", "nodes": [], "transitions": [{"from": "START", "to": 3}]})"));
  CHECK(error == "transitions[0].to: expected a string");
  const auto ok = graph(R"({"training": "t", "nodes": [{"name": "a", "task": "x.yaml"}],
                            "transitions": [{"from": "START", "to": "a", "if": ""}, {"from": "a", "to": "END", "if": "score GE 3"}]})");
  REQUIRE(ok);
  CHECK(ok->nodes[0].max_attempts == 3);
  CHECK_FALSE(ok->transitions[0].condition);
  CHECK(ok->transitions[1].condition->text == "score GE 3");
}

TEST_CASE("the Training Builder's endpoints read, check, save and refuse a file changed on disk", "[instructor][builder]") {
  BuilderFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  const std::string url = "/api/builder/training/fig10_training.yaml";
  CHECK(http.Get("/api/builder/trainings")->status == 401);
  CHECK(http.Get(url)->status == 401);
  CHECK(http.Post(url, "{}", "application/json")->status == 401);
  http.set_default_headers(f.auth());
  const auto listing = parse_json(http.Get("/api/builder/trainings", f.auth())->body);
  REQUIRE(listing["trainings"].size() == 1);
  CHECK(listing["trainings"][0]["file"].asString() == "fig10_training.yaml");
  CHECK(listing["tasks"].size() == 3);
  CHECK(text(listing["ops"]) == text(parse_json(R"(["LT","LE","GT","GE","EQ","NE"])")));
  const auto opened = parse_json(http.Get(url, f.auth())->body);
  CHECK(opened["version"].asString() == rise::instructor::content_version(slurp(f.training())));
  CHECK(opened["check"]["ok"].asBool());
  Json::Value graph = opened["graph"];
  CHECK(graph["transitions"][1]["comment"].asString() == "C3: Mission 2 not needed");
  const std::string version = opened["version"].asString();

  SECTION("a check names the loader's errors with line and key, and a bad graph is not saved (422)") {
    graph["transitions"][2]["if"] = "score GE lots";
    auto r = http.Post(url + "/check", save_body(graph, version), "application/json");
    const auto check = parse_json(r->body);
    REQUIRE(check["errors"].size() == 1);
    CHECK(check["errors"][0]["key"].asString() == "transitions[2].if");
    CHECK(check["errors"][0]["message"].asString() == "condition 'score GE lots': 'lots' is not a number");
    const int line = check["errors"][0]["line"].asInt();
    // That line of the YAML it would save holds that transition.
    std::istringstream yaml(check["yaml"].asString());
    std::string l;
    for (int i = 0; i < line; ++i) std::getline(yaml, l);
    CHECK(l.find("score GE lots") != std::string::npos);
    const std::string before = slurp(f.training());
    r = http.Post(url, save_body(graph, version), "application/json");
    CHECK(r->status == 422);
    CHECK(slurp(f.training()) == before);
  }
  SECTION("a graph-level error: the node it belongs to as key") {
    Json::Value n;
    n["name"] = "drill";
    n["task"] = "neutralize_object.yaml";
    graph["nodes"].append(n);
    const auto check = parse_json(http.Post(url + "/check", save_body(graph, version), "application/json")->body);
    REQUIRE(check["errors"].size() == 1);
    CHECK(check["errors"][0]["key"].asString() == "nodes[3]");
    CHECK(check["errors"][0]["message"].asString() == "node 'drill' is unreachable from START");
  }
  SECTION("a task outside the folder is refused before anything reads it") {
    graph["nodes"][0]["task"] = "/etc/passwd";
    const auto check = parse_json(http.Post(url + "/check", save_body(graph, version), "application/json")->body);
    REQUIRE(check["errors"].size() == 1);
    CHECK(check["errors"][0]["key"].asString() == "nodes[0].task");
  }
  SECTION("saved at the version read, then 409 once someone else wrote the file") {
    graph["nodes"][1]["max_attempts"] = 5;
    auto r = http.Post(url, save_body(graph, version), "application/json");
    REQUIRE(r->status == 200);
    const auto saved = parse_json(r->body);
    CHECK(saved["version"].asString() == rise::instructor::content_version(slurp(f.training())));
    const auto g = rise::sim::training::load_training_graph(f.training().string());
    CHECK(g.nodes[1].max_attempts == 5);
    CHECK(g.transitions[1].comment == "C3: Mission 2 not needed");
    // The same version again: the file is no longer at it.
    r = http.Post(url, save_body(graph, version), "application/json");
    CHECK(r->status == 409);
    std::ofstream(f.training(), std::ios::app) << "# someone else\n";
    const std::string theirs = slurp(f.training());
    r = http.Post(url, save_body(graph, saved["version"].asString()), "application/json");
    REQUIRE(r->status == 409);
    const auto conflict = parse_json(r->body);
    CHECK(conflict["error"].asString().find("changed on disk since this page loaded it") != std::string::npos);
    CHECK(conflict["current_version"].asString() == rise::instructor::content_version(theirs));
    CHECK(slurp(f.training()) == theirs);
    // Overwriting knowingly: with the version on disk now.
    CHECK(http.Post(url, save_body(graph, conflict["current_version"].asString()), "application/json")->status == 200);
  }
  SECTION("a file whose graph has errors opens with them listed; one of the wrong form shows its error") {
    std::ofstream(f.dir / "designs" / "broken.yaml")
        << "training: broken\nnodes:\n  - {name: a, task: approach_object.yaml}\n  - {name: b, task: "
           "approach_object.yaml}\ntransitions:\n  - {from: START, to: a}\n  - {from: a, to: END}\n";
    const auto broken = parse_json(http.Get("/api/builder/training/broken.yaml", f.auth())->body);
    CHECK(broken["graph"]["nodes"].size() == 2);
    REQUIRE(broken["check"]["errors"].size() == 1);
    CHECK(broken["check"]["errors"][0]["key"].asString() == "nodes[1]");
    CHECK(broken["check"]["errors"][0]["message"].asString() == "node 'b' is unreachable from START");
    std::ofstream(f.dir / "designs" / "form.yaml") << "training: t\nnodes: 3\n";
    const auto form = parse_json(http.Get("/api/builder/training/form.yaml", f.auth())->body);
    CHECK_FALSE(form.isMember("graph"));
    CHECK(form["load_error"].asString().find("form.yaml:2: nodes: expected a non-empty list") != std::string::npos);
  }
  SECTION("no file outside the folder, no body of the wrong shape") {
    CHECK(http.Get("/api/builder/training/..%2Finstructor.key", f.auth())->status != 200);
    CHECK(http.Get("/api/builder/training/missing.yaml", f.auth())->status == 404);
    CHECK(http.Post(url, "not json", "application/json")->status != 200);
    CHECK(http.Post(url, R"({"graph": {"training": "t", "nodes": 1}})", "application/json")->status == 400);
  }
  server.stop();
}
