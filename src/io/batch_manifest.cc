#include "rotorid/io/batch_manifest.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/yaml_fields.h"
#include "rotorid/core/error.h"
#include "rotorid/io/yaml_document.h"

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

// Log, vehicle, window and options: a sweep lists one log several times with different options.
std::string KeyOf(const std::string& log, const std::string& vehicle, const nlohmann::json& window,
                  const nlohmann::json& options) {
  return nlohmann::json{log, vehicle, window, options.empty() ? nlohmann::json::object() : options}.dump();
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
      entry.options.emplace_back(Scalar(source, option.first, "an option's name"), std::move(values));
    }
  }
  for (const auto& field : node) {
    const std::string key = Scalar(source, field.first, "a key");
    if (key != "vehicle" && key != "log" && key != "window" && key != "options")
      internal::FailAt(source, field.first, "unknown key '" + key + "' (vehicle, log, window, options)");
  }
  return entry;
}

}  // namespace

std::string BatchEntry::Key() const { return KeyOf(log, vehicle, WindowJson(window), OptionsJson()); }

nlohmann::json BatchEntry::OptionsJson() const {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, values] : options) out[name] = values;
  return out;
}

std::vector<BatchEntry> ReadBatchManifest(const std::string& path) {
  // A manifest lists thousands of logs: 4 MB, about 50 000 entries.
  return ParseBatchManifest(ReadFile(path, std::uint64_t{4} << 20), path);
}

std::vector<BatchEntry> ParseBatchManifest(const std::string& text, const std::string& path) {
  const YAML::Node root = internal::LoadYaml(text, path);
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
  const nlohmann::json options = j.value("options", nlohmann::json::object());
  return KeyOf(j["log"], j["vehicle"], j.value("window", nlohmann::json()), options);
}

BatchOutput ReadBatchOutput(const std::string& output_path) {
  BatchOutput output;
  std::ifstream in(output_path);
  std::string line;
  while (std::getline(in, line)) {
    // A last line without its newline was cut short, even when what was written parses.
    const auto key = in.eof() ? std::nullopt : BatchLineKey(line);
    if (!key) {
      output.broken_lines += line.empty() ? 0 : 1;
      continue;
    }
    output.done.insert(*key);
    output.complete_lines += line + "\n";
  }
  return output;
}

}  // namespace rotorid
