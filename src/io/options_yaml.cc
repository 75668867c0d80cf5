#include "rotorid/io/options_yaml.h"

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/yaml_document.h"

namespace rotorid {

namespace {

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

std::vector<OptionSetting> ParseOptionsYaml(const std::string& text, const std::string& source) {
  if (text.size() > kMaxYamlFileBytes)
    throw Error("--config: larger than " + std::to_string(kMaxYamlFileBytes >> 20) + " MB: is it the right file?");
  const YAML::Node root = LoadYaml(text, source);
  if (root.IsNull()) return {};
  if (!root.IsMap()) throw Error("--config: the file must be a map of option: value");
  std::vector<OptionSetting> settings;
  for (const auto& entry : root) {
    OptionSetting setting;
    if (!entry.first.IsScalar()) throw Error(source + ": the keys are option names");
    setting.name = entry.first.as<std::string>();
    while (!setting.name.empty() && setting.name[0] == '-') setting.name.erase(0, 1);
    const YAML::Node& value = entry.second;
    const std::string not_a_value = "--config: '" + setting.name + "' must be a value or a list of values";
    if (value.IsScalar()) {
      setting.values.push_back(value.as<std::string>());
    } else if (value.IsSequence()) {
      for (const auto& element : value) {
        if (!element.IsScalar()) throw Error(not_a_value);
        setting.values.push_back(element.as<std::string>());
      }
    } else {
      throw Error(not_a_value);
    }
    settings.push_back(std::move(setting));
  }
  return settings;
}

nlohmann::json OptionsFileJson(const std::string& path) {
  try {
    return {{"file", path}, {"options", YamlJson(LoadYamlFile(path))}};
  } catch (const YAML::Exception& e) {
    throw Error(path + ": " + e.what());
  }
}

}  // namespace rotorid
