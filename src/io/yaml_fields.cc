#include "io/yaml_fields.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <string_view>

#include "rotorid/core/error.h"

namespace rotorid::internal {

namespace {

// Walks the tree as its readers will, aliases expanded, within a budget of nodes. yaml-cpp keeps
// both entries of a repeated key and lookups see only one: an error instead.
class TreeCheck {
 public:
  TreeCheck(const std::string& source, size_t text_size) : source_(source), budget_(2 * text_size + 1000) {}

  void Visit(const YAML::Node& node, int depth = 0) {
    if (++visited_ > budget_)
      FailAt(source_, node,
             "aliases (*name) expand this document beyond " + std::to_string(budget_) +
                 " nodes: write the values out instead of repeating anchors");
    // Anchors chained through aliases nest without bound (and each reader recurses).
    if (depth > kMaxDepth) FailAt(source_, node, "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    if (node.IsSequence()) {
      for (const YAML::Node& item : node) Visit(item, depth + 1);
    } else if (node.IsMap()) {
      std::set<std::string> keys;
      for (const auto& entry : node) {
        Visit(entry.first, depth + 1);
        if (entry.first.IsScalar() && !keys.insert(entry.first.Scalar()).second)
          FailAt(source_, entry.first, "duplicate key '" + entry.first.Scalar() + "'");
        Visit(entry.second, depth + 1);
      }
    }
  }

 private:
  static constexpr int kMaxDepth = 200;
  const std::string& source_;
  const size_t budget_;
  size_t visited_ = 0;
};

// The line (1-based) where a second document starts, 0 when there is none: a `---` after content, or
// content after a `...` end marker. By the lines, since yaml-cpp 0.7's LoadAll never returns on some
// inputs (",e,").
int SecondDocumentLine(const std::string& text) {
  // Whether `line` from `from` on holds more than blanks and a comment.
  const auto holds_content = [](std::string_view line, size_t from) {
    const size_t first = line.find_first_not_of(" \t\r", from);
    return first != std::string_view::npos && line[first] != '#';
  };
  bool content = false, ended = false;
  int number = 0;
  for (size_t start = 0; start < text.size(); ++number) {
    const size_t end = std::min(text.find('\n', start), text.size());
    const std::string_view line(text.data() + start, end - start);
    start = end + 1;
    const auto marker = [&line](const char* m) {
      return line.compare(0, 3, m) == 0 && (line.size() == 3 || line[3] == ' ' || line[3] == '\t' || line[3] == '\r');
    };
    if (marker("---")) {
      if (content || ended) return number + 1;
      content = holds_content(line, 3);
    } else if (marker("...")) {
      ended = content;
    } else if (!line.empty() && line[0] != '%' && holds_content(line, 0)) {
      if (ended) return number + 1;
      content = true;
    }
  }
  return 0;
}

}  // namespace

void FailAt(const std::string& source, const YAML::Node& node, const std::string& message) {
  const YAML::Mark mark = node.Mark();
  throw Error(Located(source, mark.is_null() ? 0 : mark.line + 1, mark.is_null() ? 0 : mark.column + 1, message));
}

double ReadYamlNumber(const std::string& source, const YAML::Node& node, const std::string& what) {
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
    FailAt(source, node, what + " must be a finite number" + (node.IsScalar() ? ", got '" + node.Scalar() + "'" : ""));
  }
  return value;
}

}  // namespace rotorid::internal

namespace rotorid {

YAML::Node LoadYaml(const std::string& text, const std::string& source) {
  if (const int line = internal::SecondDocumentLine(text); line > 0)
    throw Error(Located(source, line, 1,
                        "a second YAML document: rotorid reads one document per file; remove it or give it its own "
                        "file"));
  try {
    const YAML::Node root = YAML::Load(text);
    internal::TreeCheck(source, text.size()).Visit(root);
    return root;
  } catch (const YAML::Exception& e) {
    throw Error(Located(source, e.mark.is_null() ? 0 : e.mark.line + 1, e.mark.is_null() ? 0 : e.mark.column + 1,
                        "not valid YAML: " + e.msg));
  }
}

YAML::Node LoadYamlFile(const std::string& path, std::uint64_t max_bytes) {
  return LoadYaml(ReadFile(path, max_bytes), path);
}

}  // namespace rotorid
