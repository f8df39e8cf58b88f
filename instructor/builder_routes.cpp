#include "instructor/builder_routes.hpp"

#include <memory>

#include "instructor/design_routes.hpp"
#include "instructor/training_builder.hpp"
#include "sim/training/training_graph.hpp"

namespace rise::instructor {

namespace {

// The Training Builder's kind of file: the training graphs (and the task
// files they name) of --designs DIR.
DesignKind training_kind() {
  DesignKind kind;
  kind.plural = "trainings";
  kind.singular = "training";
  kind.flag = "--designs DIR";
  kind.list = [](const DesignFolder& folder) { return training_files_json(folder.dir(), folder.list(".yaml")); };
  kind.read = [](const std::string& text, const std::string& path) {
    // Unvalidated: a graph with errors opens, and the check lists them
    // beside its entries as rise-trainer check would (tasks loaded).
    const auto g = sim::training::parse_training_graph(text, path, false, false);
    Json::Value v;
    v["graph"] = training_graph_json(g);
    v["check"] = check_json(check_training(g, path));
    return v;
  };
  kind.check = [](const Json::Value& body, const std::string& path, const std::string&,
                  std::string* error) -> std::optional<DesignCheck> {
    auto graph = training_graph_from_json(body["graph"], error);
    if (!graph) return *error = "graph: " + *error, std::nullopt;
    TrainingCheck check = check_training(*graph, path);
    return DesignCheck{std::move(check.yaml), std::move(check.errors), Json::Value()};
  };
  return kind;
}

}  // namespace

void add_builder_routes(httplib::Server& http, const std::string& designs_dir) {
  add_design_routes(http, std::make_shared<DesignFolder>(designs_dir), training_kind());
}

}  // namespace rise::instructor
