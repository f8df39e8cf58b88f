#include "sim/collada_geometry.hpp"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rise::sim {
namespace {

bool named(const xmlNode* n, std::string_view name) {
  return n->type == XML_ELEMENT_NODE && std::string_view(reinterpret_cast<const char*>(n->name)) == name;
}

std::vector<const xmlNode*> elements(const xmlNode* parent, std::string_view name) {
  std::vector<const xmlNode*> out;
  for (const xmlNode* c = parent->children; c; c = c->next)
    if (named(c, name)) out.push_back(c);
  return out;
}

const xmlNode* first(const xmlNode* parent, std::string_view name) {
  const auto all = elements(parent, name);
  return all.empty() ? nullptr : all.front();
}

// libxml2 hands out strings the caller frees.
std::string taken(xmlChar* s) {
  std::string out = s ? reinterpret_cast<const char*>(s) : "";
  xmlFree(s);
  return out;
}

bool has(const xmlNode* n, const char* name) { return xmlHasProp(n, reinterpret_cast<const xmlChar*>(name)) != nullptr; }
std::string attribute(const xmlNode* n, const char* name) {
  return taken(xmlGetNoNsProp(n, reinterpret_cast<const xmlChar*>(name)));
}

// XML's white space only: a \v or \f inside a number list makes a word bad.
std::vector<std::string> words(const std::string& text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while ((at = text.find_first_not_of(" \t\n\r", at)) != std::string::npos) {
    const std::size_t end = std::min(text.find_first_of(" \t\n\r", at), text.size());
    out.push_back(text.substr(at, end - at));
    at = end;
  }
  return out;
}

// A word or attribute of the file in an error: quoted, at most 40 bytes.
std::string quoted(const std::string& s) { return "\"" + s.substr(0, 40) + (s.size() > 40 ? "...\"" : "\""); }

std::string tag_of(const xmlNode* n) { return "<" + std::string(reinterpret_cast<const char*>(n->name)) + ">"; }

std::string number_text(double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, end);
}

struct Positions {
  std::vector<double> xyz;  ///< three per position
  std::size_t count() const { return xyz.size() / 3; }
};

class Rewriter {
 public:
  explicit Rewriter(std::string where) : where_(std::move(where)) {}

  std::string document(const xmlNode* root) {
    if (!named(root, "COLLADA")) fail(root, "the root element is " + tag_of(root) + ", not <COLLADA>");
    out_ = "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
           "<COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">";
    if (const xmlNode* asset = first(root, "asset")) write_asset(asset);
    out_ += "<library_geometries>";
    for (const xmlNode* library : elements(root, "library_geometries"))
      for (const xmlNode* geometry : elements(library, "geometry")) write_geometry(geometry);
    out_ += "</library_geometries><library_visual_scenes>";
    write_scene(root);
    out_ += "</library_visual_scenes><scene><instance_visual_scene url=\"#s\"/></scene></COLLADA>\n";
    return out_;
  }

 private:
  [[noreturn]] void fail(const xmlNode* at, const std::string& what) const {
    throw std::runtime_error(where_ + ":" + std::to_string(xmlGetLineNo(at)) + ": " + what);
  }

  uint64_t count_of(const xmlNode* n, const std::string& word, const std::string& what) const {
    uint64_t v = 0;
    const char* end = word.data() + word.size();
    const auto [stop, ec] = std::from_chars(word.data(), end, v);
    if (word.empty() || word.size() > 9 || ec != std::errc() || stop != end)
      fail(n, what + " " + quoted(word) + " is not a count (up to 9 digits)");
    return v;
  }

  uint64_t count_attribute(const xmlNode* n, const char* name, uint64_t otherwise) const {
    if (!has(n, name)) return otherwise;
    const std::string tag = tag_of(n);
    return count_of(n, attribute(n, name), tag.substr(0, tag.size() - 1) + " " + name + ">");
  }

  double number_of(const xmlNode* n, std::string word) const {
    if (word.size() > 1 && word[0] == '+' && word[1] != '-') word.erase(0, 1);  // xs:double allows a sign
    double v = 0;
    const char* end = word.data() + word.size();
    const auto [stop, ec] = std::from_chars(word.data(), end, v);
    if (word.empty() || ec != std::errc() || stop != end || !std::isfinite(v))
      fail(n, tag_of(n) + " holds " + quoted(word) + ", not a finite number");
    return v;
  }

  std::vector<double> numbers(const xmlNode* n) const {
    std::vector<double> out;
    for (const std::string& w : words(taken(xmlNodeGetContent(n)))) out.push_back(number_of(n, w));
    return out;
  }

  // "#id" → id.
  std::string reference(const xmlNode* n, const char* name) const {
    const std::string ref = attribute(n, name);
    if (ref.size() < 2 || ref[0] != '#') fail(n, std::string(name) + "=" + quoted(ref) + " is not a reference (#id)");
    return ref.substr(1);
  }

  void write_asset(const xmlNode* asset) {
    out_ += "<asset>";
    if (const xmlNode* unit = first(asset, "unit"); unit && has(unit, "meter")) {
      const double metre = number_of(unit, attribute(unit, "meter"));
      if (!(metre > 0)) fail(unit, "<unit meter> must be above 0");
      out_ += "<unit meter=\"" + number_text(metre) + "\"/>";
    }
    if (const xmlNode* up = first(asset, "up_axis")) {
      const auto w = words(taken(xmlNodeGetContent(up)));
      if (w.size() != 1 || (w[0] != "X_UP" && w[0] != "Y_UP" && w[0] != "Z_UP")) fail(up, "<up_axis> is X_UP, Y_UP or Z_UP");
      out_ += "<up_axis>" + w[0] + "</up_axis>";
    }
    out_ += "</asset>";
  }

  // A <source>'s positions: its accessor's first three named params (X, Y,
  // Z) of `count` strides from `offset` in a <float_array> of the mesh.
  Positions positions_of(const xmlNode* source, const std::map<std::string, const xmlNode*>& arrays) const {
    const xmlNode* common = first(source, "technique_common");
    const xmlNode* accessor = common ? first(common, "accessor") : nullptr;
    if (!accessor) fail(source, "<source> without <technique_common><accessor>");
    const auto array = arrays.find(reference(accessor, "source"));
    if (array == arrays.end()) fail(accessor, "<accessor source> names no <float_array> of this mesh");
    const std::vector<double> values = numbers(array->second);
    if (!has(array->second, "count") || count_attribute(array->second, "count", 0) != values.size())
      fail(array->second, "<float_array count> must be the count of its numbers, " + std::to_string(values.size()));
    const uint64_t count = count_attribute(accessor, "count", 0), stride = count_attribute(accessor, "stride", 1),
                   offset = count_attribute(accessor, "offset", 0);
    std::vector<uint64_t> component;
    const auto params = elements(accessor, "param");
    for (std::size_t i = 0; i < params.size(); ++i)
      if (has(params[i], "name")) component.push_back(i);
    if (component.size() < 3 || params.size() > stride)
      fail(accessor, "a position <accessor> has three named <param>s (X, Y, Z) within its stride");
    if (count == 0 || offset + (count - 1) * stride + component[2] >= values.size())
      fail(accessor, "<accessor count=\"" + std::to_string(count) + "\"> reaches past its <float_array> of " +
                         std::to_string(values.size()));
    Positions p;
    for (uint64_t i = 0; i < count; ++i)
      for (int k = 0; k < 3; ++k) p.xyz.push_back(values[offset + i * stride + component[k]]);
    return p;
  }

  // The mesh's <vertices> positions, and the id its primitives name.
  std::pair<std::string, Positions> vertices_of(const xmlNode* mesh) const {
    std::map<std::string, const xmlNode*> arrays, sources;
    for (const xmlNode* source : elements(mesh, "source")) {
      if (has(source, "id")) sources.emplace(attribute(source, "id"), source);
      for (const xmlNode* array : elements(source, "float_array"))
        if (has(array, "id")) arrays.emplace(attribute(array, "id"), array);
    }
    const xmlNode* vertices = first(mesh, "vertices");
    if (!vertices || !has(vertices, "id")) fail(mesh, "<mesh> without <vertices id>");
    for (const xmlNode* input : elements(vertices, "input")) {
      if (attribute(input, "semantic") != "POSITION") continue;
      const auto source = sources.find(reference(input, "source"));
      if (source == sources.end()) fail(input, "the POSITION <input source> names no <source> of this mesh");
      return {attribute(vertices, "id"), positions_of(source->second, arrays)};
    }
    fail(vertices, "<vertices> without a POSITION <input>");
  }

  // A <triangles> or <polylist>: its polygons' sizes and their position
  // indices (those at the VERTEX input's offset), each checked.
  void write_primitive(const xmlNode* primitive, const std::string& vertices_id, const Positions& positions,
                       const std::string& vertices_ref) {
    const bool triangles = named(primitive, "triangles");
    const std::string tag = triangles ? "triangles" : "polylist";
    if (!has(primitive, "count")) fail(primitive, "<" + tag + "> needs count=\"N\"");
    const uint64_t count = count_attribute(primitive, "count", 0);
    uint64_t stride = 1, vertex_offset = 0;
    bool vertex = false;
    for (const xmlNode* input : elements(primitive, "input")) {
      if (!has(input, "offset")) fail(input, "<" + tag + "><input> needs offset=\"N\"");
      const uint64_t offset = count_attribute(input, "offset", 0);
      stride = std::max(stride, offset + 1);
      if (attribute(input, "semantic") != "VERTEX") continue;
      if (reference(input, "source") != vertices_id) fail(input, "the VERTEX <input source> is not this mesh's <vertices>");
      vertex = true;
      vertex_offset = offset;
    }
    if (!vertex) fail(primitive, "<" + tag + "> without a VERTEX <input>");
    // The polygons' sizes: count 3s for <triangles> (not made: a count is
    // up to 9 digits), the <vcount>s for a <polylist>.
    std::vector<uint64_t> vcount;
    uint64_t corners = 3 * count;
    if (!triangles) {
      const xmlNode* list = first(primitive, "vcount");
      if (!list && count > 0) fail(primitive, "<polylist> without <vcount>");
      if (list)
        for (const std::string& w : words(taken(xmlNodeGetContent(list)))) vcount.push_back(count_of(list, w, "<vcount>"));
      if (vcount.size() != count)
        fail(primitive, "<polylist count=\"" + std::to_string(count) + "\"> has " + std::to_string(vcount.size()) + " <vcount>s");
      corners = 0;
      for (uint64_t n : vcount) corners += n;
    }
    const auto ps = elements(primitive, "p");
    if (ps.size() > 1) fail(ps[1], "<" + tag + "> has one <p>");
    std::vector<uint64_t> indices;
    if (!ps.empty())
      for (const std::string& w : words(taken(xmlNodeGetContent(ps[0])))) indices.push_back(count_of(ps[0], w, "<p> index"));
    // corners × stride can pass 2^64 (both up to 10^9 and more): divide.
    const bool fits = corners == 0 ? indices.empty() : indices.size() % corners == 0 && indices.size() / corners == stride;
    if (!fits)
      fail(ps.empty() ? primitive : ps[0], "<" + tag + " count=\"" + std::to_string(count) + "\"> needs " + std::to_string(corners) + " × " +
                                               std::to_string(stride) + " indices in its <p>, not " + std::to_string(indices.size()));
    std::string vcounts, p;
    uint64_t kept = 0, corner = 0;
    for (uint64_t polygon = 0; polygon < (triangles ? count : vcount.size()); ++polygon) {
      const uint64_t s = triangles ? 3 : vcount[polygon];
      for (uint64_t k = 0; k < s; ++k) {
        const uint64_t i = indices[(corner + k) * stride + vertex_offset];
        if (i >= positions.count())
          fail(ps[0], "<p> index " + std::to_string(i) + " names no position (the mesh has " + std::to_string(positions.count()) + ")");
        if (s >= 3) p += std::to_string(i) + " ";
      }
      corner += s;
      if (s < 3) continue;  // a point or a line: no face
      ++kept;
      vcounts += std::to_string(s) + " ";
    }
    if (kept == 0) return;
    out_ += "<" + tag + " count=\"" + std::to_string(kept) + "\"><input semantic=\"VERTEX\" source=\"#" + vertices_ref + "\" offset=\"0\"/>";
    if (!triangles) out_ += "<vcount>" + vcounts + "</vcount>";
    out_ += "<p>" + p + "</p></" + tag + ">";
  }

  void write_geometry(const xmlNode* geometry) {
    const xmlNode* mesh = first(geometry, "mesh");
    if (!mesh || !has(geometry, "id")) return;  // a spline or a convex hull; one nothing can instance
    const auto [vertices_id, positions] = vertices_of(mesh);
    const std::string id = "g" + std::to_string(written_++);
    const std::size_t start = out_.size();
    out_ += "<geometry id=\"" + id + "\"><mesh><source id=\"" + id + "p\"><float_array id=\"" + id + "a\" count=\"" +
            std::to_string(positions.xyz.size()) + "\">";
    for (double v : positions.xyz) out_ += number_text(v) + " ";
    out_ += "</float_array><technique_common><accessor source=\"#" + id + "a\" count=\"" + std::to_string(positions.count()) +
            "\" stride=\"3\"><param name=\"X\" type=\"float\"/><param name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/>"
            "</accessor></technique_common></source><vertices id=\"" + id + "v\"><input semantic=\"POSITION\" source=\"#" + id +
            "p\"/></vertices>";
    const std::size_t faces = out_.size();
    for (const xmlNode* c = mesh->children; c; c = c->next) {
      if (named(c, "triangles") || named(c, "polylist")) write_primitive(c, vertices_id, positions, id + "v");
      for (const char* other : {"polygons", "tristrips", "trifans"})
        if (named(c, other)) fail(c, "<" + std::string(other) + "> is not read: only <triangles> and <polylist>");
    }
    std::string& name = geometries_[attribute(geometry, "id")];
    if (out_.size() == faces) {  // no faces: nothing to instance
      out_.resize(start);
      return;
    }
    name = id;
    out_ += "</mesh></geometry>";
  }

  void write_node(const xmlNode* node) {
    out_ += "<node>";
    static const std::map<std::string_view, std::size_t> transforms = {{"matrix", 16}, {"translate", 3}, {"rotate", 4}, {"scale", 3}};
    for (const xmlNode* c = node->children; c; c = c->next) {
      if (c->type != XML_ELEMENT_NODE) continue;
      const std::string_view tag = reinterpret_cast<const char*>(c->name);
      if (const auto t = transforms.find(tag); t != transforms.end()) {
        const std::vector<double> v = numbers(c);
        if (v.size() != t->second) fail(c, "<" + std::string(tag) + "> holds " + std::to_string(t->second) + " numbers");
        out_ += "<" + std::string(tag) + ">";
        for (double x : v) out_ += number_text(x) + " ";
        out_ += "</" + std::string(tag) + ">";
      } else if (tag == "lookat" || tag == "skew" || tag == "instance_node") {
        fail(c, "<" + std::string(tag) + "> is not read");
      } else if (tag == "instance_geometry") {
        const auto g = geometries_.find(reference(c, "url"));
        if (g == geometries_.end()) fail(c, "<instance_geometry url> names no <geometry>");
        if (!g->second.empty()) out_ += "<instance_geometry url=\"#" + g->second + "\"/>";
      } else if (tag == "node") {
        write_node(c);
      }
    }
    out_ += "</node>";
  }

  // The scene's visual scene (<scene><instance_visual_scene url>, else the first).
  void write_scene(const xmlNode* root) {
    std::vector<const xmlNode*> scenes;
    for (const xmlNode* library : elements(root, "library_visual_scenes"))
      for (const xmlNode* s : elements(library, "visual_scene")) scenes.push_back(s);
    const xmlNode* chosen = scenes.empty() ? nullptr : scenes.front();
    const xmlNode* scene = first(root, "scene");
    if (const xmlNode* instance = scene ? first(scene, "instance_visual_scene") : nullptr) {
      const std::string id = reference(instance, "url");
      chosen = nullptr;
      for (const xmlNode* s : scenes)
        if (!chosen && attribute(s, "id") == id) chosen = s;
      if (!chosen) fail(instance, "<instance_visual_scene url> names no <visual_scene>");
    }
    if (!chosen) fail(root, "no <visual_scene>");
    out_ += "<visual_scene id=\"s\">";
    for (const xmlNode* node : elements(chosen, "node")) write_node(node);
    out_ += "</visual_scene>";
  }

  std::string where_;
  std::string out_;
  std::map<std::string, std::string> geometries_;  ///< the file's id → ours ("" for one left out)
  int written_ = 0;
};

void quiet(void*, const char*, ...) {}

}  // namespace

std::string plain_collada(const std::string& bytes, const std::string& where) {
  xmlInitParser();
  // Its encoding layer reports through the generic handler whatever the
  // options say: keep stderr for our one-line error (the handler is per thread).
  xmlSetGenericErrorFunc(nullptr, quiet);
  const std::unique_ptr<xmlParserCtxt, decltype(&xmlFreeParserCtxt)> parser(xmlNewParserCtxt(), xmlFreeParserCtxt);
  if (!parser) throw std::runtime_error(where + ": out of memory for the XML parser");
  if (bytes.size() > INT_MAX) throw std::runtime_error(where + ": over 2 GB");
  const int options = XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING | XML_PARSE_BIG_LINES | XML_PARSE_NOCDATA;
  const std::unique_ptr<xmlDoc, decltype(&xmlFreeDoc)> doc(
      xmlCtxtReadMemory(parser.get(), bytes.data(), static_cast<int>(bytes.size()), nullptr, nullptr, options), xmlFreeDoc);
  if (!doc) {
    const xmlError* e = xmlCtxtGetLastError(parser.get());
    std::string message = e && e->message ? e->message : "unreadable";
    while (!message.empty() && message.back() == '\n') message.pop_back();
    throw std::runtime_error(where + ":" + std::to_string(e ? e->line : 0) + ": not XML: " + message);
  }
  const xmlNode* root = xmlDocGetRootElement(doc.get());
  if (doc->intSubset) throw std::runtime_error(where + ": a <!DOCTYPE> is not read");
  if (!root) throw std::runtime_error(where + ": no root element");
  return Rewriter(where).document(root);
}

}  // namespace rise::sim
