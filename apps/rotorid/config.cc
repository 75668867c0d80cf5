// --config FILE.yaml: any long option of a subcommand as a YAML key (without the dashes), a list
// for a repeatable option. Options on the command line take precedence over the file.
//
//   # identify.yaml
//   vehicle: [A.yaml, B.yaml]
//   log: [a.csv, b.csv]
//   cutoff-hz: 8
//   all-parameters: true

#include <yaml-cpp/yaml.h>

#include <fstream>

#include "commands.h"
#include "rotorid/core/error.h"

namespace rotorid::cli {

namespace {

class YamlConfig : public CLI::Config {
 public:
  // Writing a config file is not offered (--help lists the keys).
  std::string to_config(const CLI::App*, bool, bool, std::string) const override { return {}; }

  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
    YAML::Node root;
    try {
      root = YAML::Load(input);
    } catch (const YAML::Exception& e) {
      throw CLI::ConfigError("--config: not valid YAML: " + std::string(e.what()));
    }
    if (root.IsNull()) return {};
    if (!root.IsMap()) throw CLI::ConfigError("--config: the file must be a map of option: value");
    std::vector<CLI::ConfigItem> items;
    for (const auto& entry : root) {
      CLI::ConfigItem item;
      item.name = entry.first.as<std::string>();
      while (!item.name.empty() && item.name[0] == '-') item.name.erase(0, 1);
      const YAML::Node& value = entry.second;
      if (value.IsScalar()) {
        item.inputs.push_back(value.as<std::string>());
      } else if (value.IsSequence()) {
        for (const auto& element : value) {
          if (!element.IsScalar())
            throw CLI::ConfigError("--config: '" + item.name + "' must be a value or a list of values");
          item.inputs.push_back(element.as<std::string>());
        }
      } else {
        throw CLI::ConfigError("--config: '" + item.name + "' must be a value or a list of values");
      }
      items.push_back(std::move(item));
    }
    return items;
  }
};

nlohmann::json ScalarJson(const YAML::Node& node) {
  const std::string text = node.as<std::string>();
  if (text == "true" || text == "false") return text == "true";
  try {
    size_t used = 0;
    const double number = std::stod(text, &used);
    if (used == text.size()) return number;
  } catch (const std::exception&) {
  }
  return text;
}

nlohmann::json YamlJson(const YAML::Node& node) {
  if (node.IsScalar()) return ScalarJson(node);
  nlohmann::json out = node.IsMap() ? nlohmann::json::object() : nlohmann::json::array();
  for (const auto& entry : node) {
    if (node.IsMap())
      out[entry.first.as<std::string>()] = YamlJson(entry.second);
    else
      out.push_back(YamlJson(entry));
  }
  return out;
}

}  // namespace

void AddConfigOption(CLI::App* app) {
  app->set_config("--config", "", "YAML file of options (keys: the long option names; lists for repeatable ones)")
      ->check(CLI::ExistingFile);
  app->config_formatter(std::make_shared<YamlConfig>());
  app->allow_config_extras(CLI::config_extras_mode::error);
}

nlohmann::json ConfigJson(const CLI::App& app) {
  const CLI::Option* option = app.get_config_ptr();
  if (option == nullptr || option->count() == 0) return nullptr;
  const std::string path = option->as<std::string>();
  try {
    return {{"file", path}, {"options", YamlJson(YAML::LoadFile(path))}};
  } catch (const YAML::Exception& e) {
    throw Error(path + ": " + e.what());
  }
}

}  // namespace rotorid::cli
