#include "report/report_reader.h"

#include <cmath>

#include "rotorid/core/error.h"
#include "rotorid/model/parameters.h"

namespace rotorid::internal {

namespace {

const char* TypeName(const nlohmann::json& j) { return j.type_name(); }

std::string Child(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

}  // namespace

void JsonNode::Fail(const std::string& what) const {
  throw Error("report JSON: " + (path_.empty() ? std::string("the document") : "'" + path_ + "'") + " " + what);
}

JsonNode JsonNode::operator[](const std::string& key) const {
  if (!j_->is_object()) Fail(std::string("is ") + TypeName(*j_) + ", not an object with key '" + key + "'");
  const auto it = j_->find(key);
  if (it == j_->end()) throw Error("report JSON: missing key '" + Child(path_, key) + "'");
  return JsonNode(*it, Child(path_, key));
}

JsonNode JsonNode::operator[](size_t index) const {
  if (!j_->is_array()) Fail(std::string("is ") + TypeName(*j_) + ", not an array");
  if (index >= j_->size()) Fail("has " + std::to_string(j_->size()) + " entries, no entry " + std::to_string(index));
  return JsonNode((*j_)[index], path_ + "[" + std::to_string(index) + "]");
}

bool JsonNode::Has(const std::string& key) const {
  if (!j_->is_object()) return false;
  const auto it = j_->find(key);
  return it != j_->end() && !it->is_null();
}

std::vector<JsonNode> JsonNode::Elements() const {
  if (!j_->is_array()) Fail(std::string("is ") + TypeName(*j_) + ", not an array");
  std::vector<JsonNode> out;
  for (size_t k = 0; k < j_->size(); ++k) out.push_back((*this)[k]);
  return out;
}

std::vector<std::pair<std::string, JsonNode>> JsonNode::Items() const {
  if (!j_->is_object()) Fail(std::string("is ") + TypeName(*j_) + ", not an object");
  std::vector<std::pair<std::string, JsonNode>> out;
  for (const auto& item : j_->items()) out.emplace_back(item.key(), JsonNode(item.value(), Child(path_, item.key())));
  return out;
}

double JsonNode::Number() const {
  if (!j_->is_number()) Fail(std::string("is ") + TypeName(*j_) + ", not a number");
  return j_->get<double>();
}

std::optional<double> JsonNode::NumberOrNull() const {
  if (j_->is_null()) return std::nullopt;
  return Number();
}

std::vector<double> JsonNode::Numbers() const {
  if (j_->is_number()) return {j_->get<double>()};
  if (!j_->is_array()) Fail(std::string("is ") + TypeName(*j_) + ", not a number or an array of numbers");
  std::vector<double> out;
  for (const JsonNode& e : Elements()) out.push_back(e.NumberOrNull().value_or(NAN));
  return out;
}

std::string JsonNode::String() const {
  if (!j_->is_string()) Fail(std::string("is ") + TypeName(*j_) + ", not a string");
  return j_->get<std::string>();
}

bool JsonNode::Bool() const {
  if (!j_->is_boolean()) Fail(std::string("is ") + TypeName(*j_) + ", not true or false");
  return j_->get<bool>();
}

std::vector<std::optional<double>> JsonNode::Components() const {
  std::vector<std::optional<double>> out(kNumWrenchComponents);
  for (int c = 0; c < kNumWrenchComponents; ++c) out[c] = (*this)[kWrenchComponentNames[c]].NumberOrNull();
  return out;
}

}  // namespace rotorid::internal
