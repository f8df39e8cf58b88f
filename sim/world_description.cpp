#include "sim/world_description.hpp"

#include "sim/yaml_reader.hpp"

namespace rise::sim {

WorldDescription default_world() {
  WorldDescription w;
  w.name = "yard";
  // A few obstacles beside the start, clear of the demo's drive (ahead, then
  // a right curve), and a wall far ahead.
  w.boxes.push_back({"crate_a", {-3.0, 3.0, 0.3}, {0.6, 0.6, 0.6}, 0.0});
  w.boxes.push_back({"crate_b", {-4.0, -3.0, 0.4}, {0.8, 0.8, 0.8}, 0.4});
  w.boxes.push_back({"barrier", {0.0, -4.0, 0.25}, {2.0, 0.2, 0.5}, 0.0});
  w.boxes.push_back({"wall_north", {25.0, 0.0, 1.0}, {0.3, 20.0, 2.0}, 0.0});
  return w;
}

WorldDescription parse_world_description(const std::string& text, const std::string& file) {
  const YamlReader r(file);
  const YAML::Node root = r.load_text(text);
  if (!root.IsMap()) r.fail(root, "", "expected a mapping with world, ground, boxes");
  r.only_keys(root, "", {"world", "ground", "boxes"});
  WorldDescription w;
  w.file = file;
  if (root["world"]) w.name = r.as<std::string>(root["world"], "world");
  if (const YAML::Node g = root["ground"]) {
    r.only_keys(g, "ground", {"friction"});
    w.ground_friction = r.positive(g, "friction", "ground", w.ground_friction);
  }
  if (const YAML::Node boxes = root["boxes"]) {
    if (!boxes.IsSequence()) r.fail(boxes, "boxes", "expected a list");
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const YAML::Node b = boxes[i];
      std::string where = "boxes[" + std::to_string(i) + "]";
      r.only_keys(b, where, {"name", "center_m", "size_m", "yaw_deg"});
      BoxObstacle box;
      if (!b["name"]) r.fail(b, where + ".name", "missing");
      box.name = r.as<std::string>(b["name"], where + ".name");
      for (const auto& existing : w.boxes)
        if (existing.name == box.name) r.fail(b["name"], where + ".name", "duplicate name '" + box.name + "'");
      for (const char* key : {"center_m", "size_m"}) {
        const YAML::Node v = b[key];
        if (!v || !v.IsSequence() || v.size() != 3) r.fail(v ? v : b, where + "." + key, "expected [x, y, z]");
        auto& out = std::string(key) == "center_m" ? box.center_m : box.size_m;
        for (std::size_t k = 0; k < 3; ++k) out[k] = r.as<double>(v[k], where + "." + key);
      }
      for (double s : box.size_m)
        if (!(s > 0)) r.fail(b["size_m"], where + ".size_m", "must be > 0");
      if (b["yaw_deg"]) box.yaw_rad = r.as<double>(b["yaw_deg"], where + ".yaw_deg") * M_PI / 180.0;
      w.boxes.push_back(box);
    }
  }
  return w;
}

WorldDescription load_world_description(const std::string& path) {
  return parse_world_description(read_text_file(path), path);
}

}  // namespace rise::sim
