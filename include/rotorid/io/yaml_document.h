#pragma once

// The one way rotorid reads YAML (vehicle files, column maps, batch manifests, --config): bounded
// in size and in alias expansion, so that no file makes a reader hang or exhaust memory.

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>

#include "rotorid/io/atomic_file.h"

namespace rotorid {

// Parses `text`; a syntax error becomes a rotorid::Error located in `source`. Refuses a repeated
// key, and aliases that expand the document beyond twice its size in nodes (an "alias bomb" of a
// few hundred bytes expands to billions: every reader that walks the tree would hang). A second
// document (after `---`) is an error, not silently ignored.
YAML::Node LoadYaml(const std::string& text, const std::string& source);
// LoadYaml of a file of at most `max_bytes`.
YAML::Node LoadYamlFile(const std::string& path, std::uint64_t max_bytes = kMaxYamlFileBytes);

}  // namespace rotorid
