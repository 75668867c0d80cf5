#pragma once

// Reading the YAML files of rotorid (vehicle files, column maps, the simulator's `simulation:`
// mapping) with errors that name file, line and column. Internal to the library.

#include <yaml-cpp/yaml.h>

#include <string>

#include "rotorid/io/yaml_document.h"

namespace rotorid::internal {

// LoadYaml and LoadYamlFile: rotorid/io/yaml_document.h.
using rotorid::LoadYaml;
using rotorid::LoadYamlFile;

// Throws rotorid::Error "source:line:column: message" at `node` (no position when it has none).
[[noreturn]] void FailAt(const std::string& source, const YAML::Node& node, const std::string& message);

// A finite number, else an error naming `what` and the offending text.
double ReadYamlNumber(const std::string& source, const YAML::Node& node, const std::string& what);

}  // namespace rotorid::internal
