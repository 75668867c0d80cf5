#include "rotorid/io/batch_manifest.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/yaml_fields.h"
#include "rotorid/core/error.h"

namespace rotorid {

namespace {

std::string ResolvePath(const std::filesystem::path& folder, const std::string& path) {
  const std::filesystem::path p(path);
  return p.is_absolute() || folder.empty() ? path : (folder / p).lexically_normal().string();
}

std::string Scalar(const std::string& source, const YAML::Node& node, const std::string& what) {
  if (!node.IsScalar()) internal::FailAt(source, node, what + " must be a single value");
  return node.as<std::string>();
}

std::string KeyOf(const std::string& log, const std::string& vehicle, const nlohmann::json& window) {
  return nlohmann::json{log, vehicle, window}.dump();
}

nlohmann::json WindowJson(const std::optional<TimeWindow>& window) {
  return window ? nlohmann::json{window->start_s, window->end_s} : nlohmann::json();
}

BatchEntry ReadEntry(const std::string& source, const YAML::Node& node, const std::filesystem::path& folder) {
  if (!node.IsMap()) internal::FailAt(source, node, "each entry of logs must be a map with vehicle and log");
  BatchEntry entry;
  for (const char* key : {"vehicle", "log"})
    if (!node[key]) internal::FailAt(source, node, std::string("entry without '") + key + "'");
  entry.vehicle = ResolvePath(folder, Scalar(source, node["vehicle"], "vehicle"));
  entry.log = ResolvePath(folder, Scalar(source, node["log"], "log"));
  if (const YAML::Node window = node["window"]) {
    if (!window.IsSequence() || window.size() != 2) internal::FailAt(source, window, "window must be [START, END]");
    entry.window = TimeWindow{internal::ReadYamlNumber(source, window[0], "window start"),
                              internal::ReadYamlNumber(source, window[1], "window end")};
    if (!(entry.window->start_s < entry.window->end_s))
      internal::FailAt(source, window, "window must start before it ends");
  }
  if (const YAML::Node options = node["options"]) {
    if (!options.IsMap()) internal::FailAt(source, options, "options must be a map of option: value");
    for (const auto& option : options) {
      std::vector<std::string> values;
      if (option.second.IsSequence()) {
        for (const auto& value : option.second) values.push_back(Scalar(source, value, "an option's value"));
      } else {
        values.push_back(Scalar(source, option.second, "an option's value"));
      }
      entry.options.emplace_back(option.first.as<std::string>(), std::move(values));
    }
  }
  for (const auto& field : node) {
    const std::string key = field.first.as<std::string>();
    if (key != "vehicle" && key != "log" && key != "window" && key != "options")
      internal::FailAt(source, field.first, "unknown key '" + key + "' (vehicle, log, window, options)");
  }
  return entry;
}

}  // namespace

std::string BatchEntry::Key() const { return KeyOf(log, vehicle, WindowJson(window)); }

std::vector<BatchEntry> ReadBatchManifest(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open the manifest");
  std::ostringstream text;
  text << in.rdbuf();
  const YAML::Node root = internal::LoadYaml(text.str(), path);
  if (!root.IsMap() || !root["logs"] || !root["logs"].IsSequence())
    throw Error(path + ": a manifest is a map with 'logs:', a list of {vehicle, log, window, options}");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::vector<BatchEntry> entries;
  for (const auto& node : root["logs"]) entries.push_back(ReadEntry(path, node, folder));
  if (entries.empty()) throw Error(path + ": 'logs:' is empty");
  return entries;
}

BatchShard ParseBatchShard(const std::string& text) {
  BatchShard shard;
  char slash = 0;
  std::string rest;
  std::istringstream in(text);
  if (!(in >> shard.index >> slash >> shard.count) || slash != '/' || (in >> rest) || shard.count < 1 ||
      shard.index < 1 || shard.index > shard.count) {
    throw Error("shard must be I/N with 1 <= I <= N, got '" + text + "'");
  }
  return shard;
}

std::vector<size_t> ShardEntries(size_t num_entries, const BatchShard& shard) {
  std::vector<size_t> positions;
  for (size_t i = static_cast<size_t>(shard.index - 1); i < num_entries; i += static_cast<size_t>(shard.count))
    positions.push_back(i);
  return positions;
}

std::optional<std::string> BatchLineKey(const std::string& line) {
  const nlohmann::json j = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object() || !j.contains("log") || !j.contains("vehicle") || !j["log"].is_string() ||
      !j["vehicle"].is_string())
    return std::nullopt;
  return KeyOf(j["log"], j["vehicle"], j.value("window", nlohmann::json()));
}

std::set<std::string> CompletedBatchEntries(const std::string& output_path) {
  std::set<std::string> keys;
  std::ifstream in(output_path);
  for (std::string line; std::getline(in, line);)
    if (const auto key = BatchLineKey(line)) keys.insert(*key);
  return keys;
}

}  // namespace rotorid
