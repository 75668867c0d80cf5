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
#include "rotorid/io/yaml_document.h"

namespace rotorid::cli {

namespace {

// The file belongs to the root (CLI11 reads config files of the root only); its keys are the
// options of the subcommand on the command line.
class YamlConfig : public CLI::Config {
 public:
  explicit YamlConfig(const CLI::App* root) : root_(root) {}

  // Writing a config file is not offered (--help lists the keys).
  std::string to_config(const CLI::App*, bool, bool, std::string) const override { return {}; }

  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
    // At most the cap, and one byte more to tell that the file is larger (a device, say).
    std::string text(kMaxYamlFileBytes + 1, '\0');
    input.read(text.data(), static_cast<std::streamsize>(text.size()));
    text.resize(static_cast<size_t>(input.gcount()));
    if (text.size() > kMaxYamlFileBytes)
      throw CLI::ConfigError("--config: larger than " + std::to_string(kMaxYamlFileBytes >> 20) +
                             " MB: is it the right file?");
    const CLI::Option* option = root_->get_config_ptr();
    const std::string source = option != nullptr && option->count() > 0 ? option->as<std::string>() : "--config";
    YAML::Node root;
    try {
      root = LoadYaml(text, source);
    } catch (const Error& e) {
      throw CLI::ConfigError(e.what());
    }
    if (root.IsNull()) return {};
    if (!root.IsMap()) throw CLI::ConfigError("--config: the file must be a map of option: value");
    std::vector<CLI::ConfigItem> items;
    for (const auto& entry : root) {
      CLI::ConfigItem item;
      if (!entry.first.IsScalar()) throw CLI::ConfigError(source + ": the keys are option names");
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
      const std::vector<CLI::App*> parsed = root_->get_subcommands();
      if (!parsed.empty()) item.parents = {parsed.front()->get_name()};
      items.push_back(std::move(item));
    }
    return items;
  }

 private:
  const CLI::App* root_;
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

void AddConfigOption(CLI::App* root) {
  root->set_config("--config", "",
                   "YAML file of the subcommand's options (keys: the long option names; lists for repeatable ones); "
                   "may follow the subcommand")
      ->check(CLI::ExistingFile);
  root->config_formatter(std::make_shared<YamlConfig>(root));
  root->allow_config_extras(CLI::config_extras_mode::error);
  // `rotorid identify --config FILE`: the subcommand passes the option it does not know to the root.
  for (CLI::App* sub : root->get_subcommands({})) sub->fallthrough();
}

nlohmann::json ConfigJson(const CLI::App& app) {
  const CLI::App* owner = &app;
  while (owner != nullptr && owner->get_config_ptr() == nullptr) owner = owner->get_parent();
  const CLI::Option* option = owner ? owner->get_config_ptr() : nullptr;
  if (option == nullptr || option->count() == 0) return nullptr;
  const std::string path = option->as<std::string>();
  try {
    return {{"file", path}, {"options", YamlJson(LoadYamlFile(path))}};
  } catch (const YAML::Exception& e) {
    throw Error(path + ": " + e.what());
  }
}

}  // namespace rotorid::cli
