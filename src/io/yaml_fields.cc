#include "io/yaml_fields.h"

#include <cmath>
#include <set>

#include "rotorid/core/error.h"

namespace rotorid::internal {

namespace {

// yaml-cpp keeps both entries of a repeated key and lookups see only one: an error instead.
void RejectDuplicateKeys(const std::string& source, const YAML::Node& node) {
  if (node.IsSequence()) {
    for (const YAML::Node& item : node) RejectDuplicateKeys(source, item);
  } else if (node.IsMap()) {
    std::set<std::string> keys;
    for (const auto& entry : node) {
      if (entry.first.IsScalar() && !keys.insert(entry.first.Scalar()).second)
        FailAt(source, entry.first, "duplicate key '" + entry.first.Scalar() + "'");
      RejectDuplicateKeys(source, entry.second);
    }
  }
}

}  // namespace

YAML::Node LoadYaml(const std::string& text, const std::string& source) {
  try {
    YAML::Node root = YAML::Load(text);
    RejectDuplicateKeys(source, root);
    return root;
  } catch (const YAML::Exception& e) {
    throw Error(Located(source, e.mark.is_null() ? 0 : e.mark.line + 1, e.mark.is_null() ? 0 : e.mark.column + 1,
                        "not valid YAML: " + e.msg));
  }
}

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
