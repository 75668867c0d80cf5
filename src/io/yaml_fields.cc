#include "io/yaml_fields.h"

#include <cmath>

#include "rotorid/core/error.h"

namespace rotorid::internal {

YAML::Node LoadYaml(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
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
