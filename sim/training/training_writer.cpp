#include "sim/training/training_writer.hpp"

#include <cstdio>
#include <sstream>

namespace rise::sim::training {

namespace {

bool plain_safe(const std::string& s) {
  if (s.empty()) return false;
  const auto c0 = static_cast<unsigned char>(s[0]);
  if (!(std::isalpha(c0) || s[0] == '_')) return false;
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (!(std::isalnum(c) || ch == '_' || ch == '.' || ch == '/' || ch == '-')) return false;
  }
  return true;
}

// A comment as the loader reads it back (training_graph.cpp): control
// characters (line breaks too) as blanks, none at the end, and for one on an
// entry's line none at the start either; so writing is a fixed point.
std::string comment_text(std::string s, bool keep_leading) {
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  const auto last = s.find_last_not_of(' ');
  if (last == std::string::npos) return "";
  s.erase(last + 1);
  if (!keep_leading) s.erase(0, s.find_first_not_of(' '));
  return s;
}

// One entry of a list: `  - {k: v, ...}` and, padded to a column, its comment.
class Lines {
 public:
  int add(const std::string& entry, const std::string& comment) {
    std::string line = entry;
    const std::string text = comment_text(comment, false);
    if (!text.empty()) {
      if (line.size() < 60) line.append(60 - line.size(), ' ');
      line += "  # " + text;
    }
    text_ += line + "\n";
    return ++count_;
  }
  void comment_block(const std::string& comment) {
    std::istringstream in(comment);
    std::string l;
    while (std::getline(in, l)) {
      l = comment_text(l, true);
      add(l.empty() ? "#" : "# " + l, "");
    }
  }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
  int count_ = 0;
};

}  // namespace

std::string yaml_scalar(const std::string& text) {
  if (plain_safe(text)) return text;
  std::string out = "\"";
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (ch == '\n') {
      out += "\\n";
    } else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

std::string write_training_graph(const TrainingGraph& g, TrainingYamlLines* where) {
  Lines out;
  TrainingYamlLines lines;
  out.comment_block(g.comment);
  out.add("training: " + yaml_scalar(g.name), "");
  if (!g.title.empty()) out.add("title: " + yaml_scalar(g.title), "");
  out.add("nodes:", "");
  for (const auto& n : g.nodes) {
    // max_attempts always written: the file says how often a node may repeat.
    const std::string task = n.task_path.empty() ? n.task_file : n.task_path;
    lines.nodes.push_back(out.add("  - {name: " + yaml_scalar(n.name) + ", task: " + yaml_scalar(task) +
                                      ", max_attempts: " + std::to_string(n.max_attempts) + "}",
                                  n.comment));
  }
  out.add("transitions:", "");
  for (const auto& t : g.transitions) {
    // The condition as written ("result LT 10" stays "result", not "score").
    const std::string cond = t.condition ? ", if: " + yaml_scalar(t.condition->text) : "";
    lines.transitions.push_back(
        out.add("  - {from: " + yaml_scalar(t.from) + cond + ", to: " + yaml_scalar(t.to) + "}", t.comment));
  }
  if (where) *where = lines;
  return out.text();
}

}  // namespace rise::sim::training
