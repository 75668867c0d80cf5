#pragma once

// Strict reading of a command's JSON report for the HTML report (internal to the report module).
// The report reads exactly the keys the writers emit (LinearJson, RefinedJson, DiagnosisJson, the
// commands' blocks): a missing key or a value of the wrong type throws rotorid::Error naming the
// key's full path ("report JSON: missing key 'where.bands[2].low_hz'"), never a silent blank.
//
//   const JsonNode report(json, "");
//   if (report.Has("baseline")) value = report["baseline"]["relative_error_pct"].Components();

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rotorid::internal {

class JsonNode {
 public:
  // `path` names `j` in messages ("" for the document's root).
  JsonNode(const nlohmann::json& j, std::string path) : j_(&j), path_(std::move(path)) {}

  // The entry `key` of an object; throws when `j` is not an object or has no such key.
  JsonNode operator[](const std::string& key) const;
  // The entry `index` of an array; throws when `j` is not an array or too short.
  JsonNode operator[](size_t index) const;
  // True when `key` is present and not null (for blocks a writer emits only sometimes).
  bool Has(const std::string& key) const;
  bool IsNull() const { return j_->is_null(); }

  // Elements of an array (throws otherwise), with their paths.
  std::vector<JsonNode> Elements() const;
  // Entries of an object (throws otherwise), in the document's order.
  std::vector<std::pair<std::string, JsonNode>> Items() const;

  double Number() const;
  // A number, or nullopt for null (keys the writers emit as null when undefined).
  std::optional<double> NumberOrNull() const;
  // A number or an array of numbers (nulls as NaN).
  std::vector<double> Numbers() const;
  std::string String() const;
  bool Bool() const;
  // {"Fx": .., "Fy": .., "Fz": .., "Mx": .., "My": .., "Mz": ..}: all six keys, numbers or null.
  std::vector<std::optional<double>> Components() const;

  const nlohmann::json& json() const { return *j_; }
  const std::string& path() const { return path_; }

 private:
  [[noreturn]] void Fail(const std::string& what) const;

  const nlohmann::json* j_;
  std::string path_;
};

}  // namespace rotorid::internal
