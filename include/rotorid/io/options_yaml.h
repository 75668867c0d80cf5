#pragma once

// The --config file (docs/cli.md): a YAML map of a subcommand's long option names (without the
// dashes) to a value, or a list of values for a repeatable option.
//
//   # identify.yaml
//   vehicle: [A.yaml, B.yaml]
//   log: [a.csv, b.csv]
//   cutoff-hz: 8
//   all-parameters: true

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace rotorid {

struct OptionSetting {
  std::string name;  // leading dashes removed
  std::vector<std::string> values;
};

// The settings of the file `source` whose content is `text` (at most kMaxYamlFileBytes), in the
// file's order; throws rotorid::Error naming the file and what is wrong.
std::vector<OptionSetting> ParseOptionsYaml(const std::string& text, const std::string& source);

// The file's options for a report's "config": {"file": path, "options": {name: value}}, values as
// JSON booleans and numbers where they read as such.
nlohmann::json OptionsFileJson(const std::string& path);

}  // namespace rotorid
