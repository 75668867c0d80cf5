// --config FILE.yaml (rotorid/io/options_yaml.h): any long option of a subcommand as a YAML key.
// Options on the command line take precedence over the file.

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/options_yaml.h"

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
    const CLI::Option* option = root_->get_config_ptr();
    const std::string source = option != nullptr && option->count() > 0 ? option->as<std::string>() : "--config";
    std::vector<CLI::ConfigItem> items;
    try {
      for (OptionSetting& setting : ParseOptionsYaml(text, source)) {
        CLI::ConfigItem item;
        item.name = std::move(setting.name);
        item.inputs = std::move(setting.values);
        const std::vector<CLI::App*> parsed = root_->get_subcommands();
        if (!parsed.empty()) item.parents = {parsed.front()->get_name()};
        items.push_back(std::move(item));
      }
    } catch (const Error& e) {
      throw CLI::ConfigError(e.what());
    }
    return items;
  }

 private:
  const CLI::App* root_;
};

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
  return OptionsFileJson(option->as<std::string>());
}

}  // namespace rotorid::cli
