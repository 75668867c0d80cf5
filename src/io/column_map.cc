#include "rotorid/io/column_map.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "io/csv_text.h"
#include "io/yaml_fields.h"
#include "rotorid/core/error.h"
#include "rotorid/core/units.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/io/rotor_signal.h"
#include "rotorid/model/rotation.h"

namespace rotorid {
namespace {

// ---- The map file ----

struct UnitEntry {
  const char* name;
  double factor;     // to SI
  bool is_command;   // a normalised command rather than a physical quantity
  double range_low;  // default command range
  double range_high;
};

// Units accepted per quantity. Commands map their range linearly onto [0, 1].
const std::vector<UnitEntry> kTimeUnits = {
    {"s", 1.0, false, 0, 1}, {"ms", 1e-3, false, 0, 1}, {"us", 1e-6, false, 0, 1}, {"ns", 1e-9, false, 0, 1}};
const std::vector<UnitEntry> kGyroUnits = {{"rad/s", 1.0, false, 0, 1}, {"deg/s", kPi / 180.0, false, 0, 1}};
const std::vector<UnitEntry> kAccUnits = {
    {"m/s^2", 1.0, false, 0, 1}, {"m/s2", 1.0, false, 0, 1}, {"g", 0.0 /* the map's gravity */, false, 0, 1}};
const std::vector<UnitEntry> kRotorUnits = {{"rad/s", 1.0, false, 0, 1},       {"rpm", 2.0 * kPi / 60.0, false, 0, 1},
                                            {"rev/s", 2.0 * kPi, false, 0, 1}, {"pwm", 1.0, true, 0, 65535},
                                            {"us", 1.0, true, 1000, 2000},     {"normalized", 1.0, true, 0, 1},
                                            {"percent", 1.0, true, 0, 100}};
const std::vector<UnitEntry> kCommandUnits = {{"pwm", 1.0, true, 0, 65535},
                                              {"us", 1.0, true, 1000, 2000},
                                              {"normalized", 1.0, true, 0, 1},
                                              {"percent", 1.0, true, 0, 100}};
const std::vector<UnitEntry> kPositionUnits = {
    {"m", 1.0, false, 0, 1}, {"cm", 1e-2, false, 0, 1}, {"mm", 1e-3, false, 0, 1}};
const std::vector<UnitEntry> kAngleUnits = {{"rad", 1.0, false, 0, 1}, {"deg", kPi / 180.0, false, 0, 1}};
const std::vector<UnitEntry> kVoltageUnits = {{"V", 1.0, false, 0, 1}, {"mV", 1e-3, false, 0, 1}};

MapLocation LocationOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.is_null()) return {};
  return {mark.line + 1, mark.column + 1};
}

[[noreturn]] void FailAt(const std::string& source, MapLocation where, const std::string& message) {
  throw Error(Located(source, where.line, where.column, message));
}

std::string UnitList(const std::vector<UnitEntry>& units) {
  std::string out;
  for (const UnitEntry& u : units) out += (out.empty() ? "" : ", ") + std::string(u.name);
  return out;
}

std::string ReadString(const std::string& source, const YAML::Node& node, const std::string& what) {
  if (!node.IsScalar()) internal::FailAt(source, node, what + " must be a string");
  return node.Scalar();
}

// Shape of a quantity: how many columns, which units.
struct QuantitySpec {
  const char* key;
  int num_columns;                      // -1: one or more (rotors)
  const std::vector<UnitEntry>* units;  // nullptr: no unit (quaternion)
  const char* example;
};

MappedQuantity ParseQuantity(const std::string& source, const YAML::Node& key, const YAML::Node& node,
                             const QuantitySpec& spec, double gravity_mps2) {
  const std::string name = spec.key;
  if (!node.IsMap()) internal::FailAt(source, node, name + " must be a mapping like " + spec.example);
  MappedQuantity q;
  q.location = LocationOf(key);
  // std::optional, not YAML::Node's own "defined" state: assigning to a Node writes through to
  // the document (reference semantics).
  std::optional<YAML::Node> column, columns, unit, scale, range;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string k = it->first.IsScalar() ? it->first.Scalar() : "";
    if (k == "column") {
      column.emplace(it->second);
    } else if (k == "columns") {
      columns.emplace(it->second);
    } else if (k == "unit") {
      unit.emplace(it->second);
    } else if (k == "scale") {
      scale.emplace(it->second);
    } else if (k == "range") {
      range.emplace(it->second);
    } else {
      internal::FailAt(source, it->first,
                       "unknown key '" + k + "' in " + name + " (known: *column, *columns, *unit, *scale, *range)");
    }
  }
  if (column && columns) internal::FailAt(source, node, name + " gives both 'column' and 'columns'; give one");
  if (column) {
    if (spec.num_columns != 1) {
      internal::FailAt(source, *column,
                       name + " needs 'columns' with " +
                           (spec.num_columns < 0 ? std::string("one per rotor") : std::to_string(spec.num_columns)) +
                           " entries, e.g. " + spec.example);
    }
    q.columns.push_back(ReadString(source, *column, name + " column"));
    q.column_locations.push_back(LocationOf(*column));
  } else if (columns) {
    if (!columns->IsSequence())
      internal::FailAt(source, *columns, name + " columns must be a list, e.g. " + std::string(spec.example));
    for (size_t i = 0; i < columns->size(); ++i) {
      q.columns.push_back(ReadString(source, (*columns)[i], name + " column " + std::to_string(i + 1)));
      q.column_locations.push_back(LocationOf((*columns)[i]));
    }
    const bool count_ok =
        spec.num_columns < 0 ? !q.columns.empty() : static_cast<int>(q.columns.size()) == spec.num_columns;
    if (!count_ok) {
      internal::FailAt(source, *columns,
                       name + " lists " + std::to_string(q.columns.size()) + " columns, expected " +
                           (spec.num_columns < 0 ? std::string("at least 1") : std::to_string(spec.num_columns)));
    }
  } else {
    internal::FailAt(source, node,
                     name + " needs '" + (spec.num_columns == 1 ? "column" : "columns") + "', e.g. " + spec.example);
  }
  for (size_t i = 0; i < q.columns.size(); ++i) {
    if (q.columns[i].empty()) FailAt(source, q.column_locations[i], name + " has an empty column name");
  }

  if (spec.units == nullptr) {
    if (unit) internal::FailAt(source, *unit, name + " takes no unit");
  } else {
    if (!unit) internal::FailAt(source, node, name + " needs a unit (" + UnitList(*spec.units) + ")");
    q.unit = ReadString(source, *unit, name + " unit");
    const auto entry =
        std::find_if(spec.units->begin(), spec.units->end(), [&](const UnitEntry& u) { return q.unit == u.name; });
    if (entry == spec.units->end()) {
      internal::FailAt(source, *unit,
                       "unknown unit '" + q.unit + "' for " + name + " (known: " + UnitList(*spec.units) + ")");
    }
    q.unit_factor = entry->factor;
    if (spec.units == &kAccUnits && q.unit == "g") q.unit_factor = gravity_mps2;
    q.is_command = entry->is_command;
    q.range_low = entry->range_low;
    q.range_high = entry->range_high;
  }
  if (scale) {
    q.scale = internal::ReadYamlNumber(source, *scale, name + " scale");
    if (q.scale == 0.0) internal::FailAt(source, *scale, name + " scale must not be zero");
  }
  if (range) {
    if (!q.is_command)
      internal::FailAt(source, *range, name + " range applies to command units only (pwm, us, normalized, percent)");
    if (!range->IsSequence() || range->size() != 2)
      internal::FailAt(source, *range, name + " range must be [low, high]");
    q.range_low = internal::ReadYamlNumber(source, (*range)[0], name + " range low");
    q.range_high = internal::ReadYamlNumber(source, (*range)[1], name + " range high");
    if (!(q.range_high > q.range_low)) internal::FailAt(source, *range, name + " range must have high > low");
  }
  return q;
}

// The quantities a map may give.
const QuantitySpec kTimeQuantity{"time", 1, &kTimeUnits, "{column: t, unit: s}"};
const QuantitySpec kGyroQuantity{"gyro", 3, &kGyroUnits, "{columns: [gx, gy, gz], unit: rad/s}"};
const QuantitySpec kAccQuantity{"acc", 3, &kAccUnits, "{columns: [ax, ay, az], unit: m/s^2}"};
const QuantitySpec kRotorsQuantity{"rotors", -1, &kRotorUnits, "{columns: [m1, m2, m3, m4], unit: rpm}"};
const QuantitySpec kCommandsQuantity{"rotor_commands", -1, &kCommandUnits, "{columns: [m1, m2, m3, m4], unit: pwm}"};
const QuantitySpec kPositionQuantity{"position", 3, &kPositionUnits, "{columns: [px, py, pz], unit: m}"};
const QuantitySpec kQuaternionQuantity{"quaternion", 4, nullptr, "{columns: [qw, qx, qy, qz]}"};
const QuantitySpec kEulerQuantity{"euler", 3, &kAngleUnits, "{columns: [roll, pitch, yaw], unit: deg}"};
const QuantitySpec kVoltageQuantity{"voltage", 1, &kVoltageUnits, "{column: vbat, unit: V}"};

// One top-level entry of the map.
struct MapEntry {
  YAML::Node key;
  YAML::Node value;
};

// The map's top-level entries by key: each key known, and given once.
class MapEntries {
 public:
  MapEntries(const YAML::Node& root, const std::string& source) {
    static const std::vector<std::string> kKeys = {
        "time",    "gyro",  "acc",         "rotors",    "rotor_commands", "position",   "quaternion", "euler",
        "voltage", "frame", "world_frame", "delimiter", "comment",        "skip_lines", "gravity",    "metadata"};
    for (auto it = root.begin(); it != root.end(); ++it) {
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : "";
      if (std::find(kKeys.begin(), kKeys.end(), key) == kKeys.end()) {
        std::string known;
        for (const auto& k : kKeys) known += (known.empty() ? "" : ", ") + k;
        internal::FailAt(source, it->first, "unknown key '" + key + "' (known: " + known + ")");
      }
      if (entries_.count(key)) internal::FailAt(source, it->first, "key '" + key + "' appears twice");
      entries_.emplace(key, MapEntry{it->first, it->second});
    }
  }

  // nullptr when the map leaves `key` out.
  const MapEntry* Find(const std::string& key) const {
    const auto it = entries_.find(key);
    return it == entries_.end() ? nullptr : &it->second;
  }
  const YAML::Node* Value(const std::string& key) const {
    const MapEntry* entry = Find(key);
    return entry ? &entry->value : nullptr;
  }

 private:
  std::map<std::string, MapEntry> entries_;
};

void ReadFrames(const MapEntries& entries, const std::string& source, ColumnMap* map) {
  if (const YAML::Node* f = entries.Value("frame")) {
    const std::string frame = ReadString(source, *f, "frame");
    if (frame == "flu") {
      map->frame = BodyFrame::kFlu;
    } else if (frame == "frd") {
      map->frame = BodyFrame::kFrd;
    } else {
      internal::FailAt(source, *f, "frame must be flu or frd, got '" + frame + "'");
    }
  }
  map->world_frame = map->frame == BodyFrame::kFrd ? WorldFrame::kNed : WorldFrame::kZUp;
  if (const YAML::Node* f = entries.Value("world_frame")) {
    const std::string frame = ReadString(source, *f, "world_frame");
    if (frame == "zup" || frame == "enu" || frame == "nwu") {
      map->world_frame = WorldFrame::kZUp;
    } else if (frame == "ned") {
      map->world_frame = WorldFrame::kNed;
    } else {
      internal::FailAt(source, *f, "world_frame must be zup (also: enu, nwu) or ned, got '" + frame + "'");
    }
  }
}

// delimiter, comment and skip_lines.
void ReadCsvLayout(const MapEntries& entries, const std::string& source, ColumnMap* map) {
  if (const YAML::Node* d = entries.Value("delimiter")) {
    const std::string delimiter = ReadString(source, *d, "delimiter");
    if (delimiter == "whitespace") {
      map->whitespace_delimited = true;
    } else if (delimiter == "tab") {
      map->delimiter = '\t';
    } else if (delimiter.size() == 1 && delimiter != "\"" && delimiter != "\n" && delimiter != "\r") {
      map->delimiter = delimiter[0];
    } else {
      internal::FailAt(source, *d, "delimiter must be one character (e.g. \",\", \";\", \"\\t\"), tab or whitespace");
    }
  }
  if (const YAML::Node* c = entries.Value("comment")) {
    map->comment = c->IsNull() ? "" : ReadString(source, *c, "comment");
  }
  if (const YAML::Node* s = entries.Value("skip_lines")) {
    const double lines = internal::ReadYamlNumber(source, *s, "skip_lines");
    if (lines < 0 || lines > 1e6 || lines != std::floor(lines)) {
      internal::FailAt(source, *s, "skip_lines must be a whole number >= 0");
    }
    map->skip_lines = static_cast<int>(lines);
  }
}

// Everything but the quantities; gravity first, since it feeds the unit g of acc.
void ReadSettings(const MapEntries& entries, const std::string& source, ColumnMap* map) {
  if (const YAML::Node* g = entries.Value("gravity")) {
    map->gravity_mps2 = internal::ReadYamlNumber(source, *g, "gravity");
    if (!(map->gravity_mps2 > 0.0)) internal::FailAt(source, *g, "gravity must be positive (m/s^2)");
  }
  ReadFrames(entries, source, map);
  ReadCsvLayout(entries, source, map);
  if (const YAML::Node* m = entries.Value("metadata")) {
    if (!m->IsMap()) internal::FailAt(source, *m, "metadata must be a mapping of key: value");
    for (auto it = m->begin(); it != m->end(); ++it) {
      map->metadata[ReadString(source, it->first, "metadata key")] = ReadString(source, it->second, "metadata value");
    }
  }
}

void ReadQuantities(const MapEntries& entries, const std::string& source, ColumnMap* map) {
  auto optional = [&](const QuantitySpec& spec) -> std::optional<MappedQuantity> {
    const MapEntry* entry = entries.Find(spec.key);
    if (!entry) return std::nullopt;
    return ParseQuantity(source, entry->key, entry->value, spec, map->gravity_mps2);
  };
  auto required = [&](const QuantitySpec& spec) {
    std::optional<MappedQuantity> quantity = optional(spec);
    if (!quantity) throw Error(source + ": missing '" + spec.key + "', e.g. " + spec.key + ": " + spec.example);
    return std::move(*quantity);
  };
  map->time = required(kTimeQuantity);
  map->gyro = required(kGyroQuantity);
  map->acc = required(kAccQuantity);
  map->rotors = optional(kRotorsQuantity);
  map->rotor_commands = optional(kCommandsQuantity);
  map->position = optional(kPositionQuantity);
  map->quaternion = optional(kQuaternionQuantity);
  map->euler = optional(kEulerQuantity);
  map->voltage = optional(kVoltageQuantity);
}

// A rotor signal, at most one second signal (commands beside speeds), and motion capture with
// both position and one orientation.
void CheckQuantitiesFitTogether(const ColumnMap& map) {
  const std::string& source = map.source;
  if (!map.rotors && !map.rotor_commands) {
    throw Error(source + ": missing 'rotors', e.g. rotors: " + kRotorsQuantity.example);
  }
  if (map.rotors && map.rotor_commands) {
    if (map.rotors->is_command) {
      FailAt(source, map.rotor_commands->location,
             "rotor_commands is a second rotor signal beside speeds; here 'rotors' already holds commands");
    }
    if (map.rotor_commands->columns.size() != map.rotors->columns.size()) {
      FailAt(source, map.rotor_commands->location,
             "rotor_commands lists " + std::to_string(map.rotor_commands->columns.size()) + " columns, rotors " +
                 std::to_string(map.rotors->columns.size()));
    }
  }
  if (map.quaternion && map.euler) {
    FailAt(source, map.euler->location, "give the orientation once: either quaternion or euler");
  }
  if (map.position && !map.quaternion && !map.euler) {
    FailAt(source, map.position->location, "position needs an orientation too: quaternion or euler");
  }
  if (!map.position && (map.quaternion || map.euler)) {
    FailAt(source, (map.quaternion ? map.quaternion : map.euler)->location,
           "an orientation needs position too (motion capture takes both)");
  }
}

}  // namespace

ColumnMap ParseColumnMap(const std::string& text, const std::string& source) {
  const YAML::Node root = internal::LoadYaml(text, source);
  if (!root.IsMap()) throw Error(source + ": a column map must be a YAML mapping with time, gyro, acc and rotors");
  const MapEntries entries(root, source);
  ColumnMap map;
  map.source = source;
  ReadSettings(entries, source, &map);
  ReadQuantities(entries, source, &map);
  CheckQuantitiesFitTogether(map);
  return map;
}

ColumnMap ReadColumnMap(const std::string& path) { return ParseColumnMap(ReadFile(path, kMaxYamlFileBytes), path); }

// ---- The CSV ----

namespace {

using internal::TextLine;
using internal::TrimSpaces;

// Splits one line into cells (trimmed; a cell in double quotes loses its quotes) and records
// where each starts (0-based), reusing the caller's buffers: no allocation per row once they
// have grown.
void SplitCells(std::string_view line, const ColumnMap& map, std::vector<std::string_view>* cells,
                std::vector<int>* starts) {
  cells->clear();
  starts->clear();
  const size_t n = line.size();
  size_t pos = 0;
  if (map.whitespace_delimited) {
    while (true) {
      while (pos < n && (line[pos] == ' ' || line[pos] == '\t' || line[pos] == '\r')) ++pos;
      if (pos >= n) return;
      const size_t start = pos;
      while (pos < n && line[pos] != ' ' && line[pos] != '\t' && line[pos] != '\r') ++pos;
      cells->push_back(line.substr(start, pos - start));
      starts->push_back(static_cast<int>(start));
    }
  }
  while (true) {
    size_t start = pos;
    while (start < n && (line[start] == ' ' || (line[start] == '\t' && map.delimiter != '\t'))) ++start;
    size_t end;
    std::string_view cell;
    if (start < n && line[start] == '"') {
      // Quoted: runs to the closing quote ("" is an escaped quote inside).
      size_t q = start + 1;
      while (q < n) {
        if (line[q] == '"') {
          if (q + 1 < n && line[q + 1] == '"') {
            q += 2;
            continue;
          }
          break;
        }
        ++q;
      }
      cell = line.substr(start + 1, std::min(q, n) - start - 1);
      end = line.find(map.delimiter, std::min(q + 1, n));
    } else {
      end = line.find(map.delimiter, start);
      cell = TrimSpaces(line.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    }
    cells->push_back(cell);
    starts->push_back(static_cast<int>(start));
    if (end == std::string_view::npos) return;
    pos = end + 1;
  }
}

bool IsSkipped(std::string_view text, const ColumnMap& map) {
  const std::string_view trimmed = TrimSpaces(text);
  if (trimmed.empty()) return true;
  return !map.comment.empty() && trimmed.substr(0, map.comment.size()) == map.comment;
}

// "map.yaml:3:22" for messages that point into the map from a CSV error.
std::string Where(const std::string& file, MapLocation at) {
  std::string out = file;
  if (at.line > 0) out += ":" + std::to_string(at.line);
  if (at.line > 0 && at.column > 0) out += ":" + std::to_string(at.column);
  return out;
}

std::string HeaderPreview(const std::vector<std::string>& names) {
  std::string out;
  for (size_t k = 0; k < names.size() && k < 24; ++k) out += (k ? ", " : "") + names[k];
  if (names.size() > 24) out += ", ... (" + std::to_string(names.size()) + " columns)";
  return out;
}

Eigen::Matrix3d FrameFlip(bool flip) {
  return flip ? Eigen::Vector3d(1, -1, -1).asDiagonal().toDenseMatrix() : Eigen::Matrix3d::Identity();
}

// Which rotor signal: speed when available (unless commands are asked for), else the command.
const MappedQuantity* ChooseRotorSignal(const ColumnMap& map, const std::string& rotor_signal, int num_rotors) {
  if (const std::string problem = RotorSignalProblem(rotor_signal); !problem.empty()) throw Error(problem);
  const MappedQuantity* speed = map.rotors && !map.rotors->is_command ? &*map.rotors : nullptr;
  const MappedQuantity* command =
      map.rotor_commands ? &*map.rotor_commands : (map.rotors && map.rotors->is_command ? &*map.rotors : nullptr);
  const MappedQuantity* rotor = nullptr;
  if (rotor_signal == "rpm") {
    if (!speed) {
      throw Error(map.source +
                  ": rotor signal 'rpm' asked for, but the map gives no rotor speeds (rotors with unit "
                  "rad/s, rpm or rev/s)");
    }
    rotor = speed;
  } else if (rotor_signal == "command") {
    if (!command) {
      throw Error(map.source +
                  ": rotor signal 'command' asked for, but the map gives no rotor commands (rotors or "
                  "rotor_commands with unit pwm, us, normalized or percent)");
    }
    rotor = command;
  } else {
    rotor = speed ? speed : command;
  }
  if (num_rotors >= 0 && static_cast<int>(rotor->columns.size()) != num_rotors) {
    FailAt(map.source, rotor->location,
           "the map lists " + std::to_string(rotor->columns.size()) + " rotor columns, the vehicle has " +
               std::to_string(num_rotors) + " rotors");
  }
  return rotor;
}

struct MappedHeader {
  int line = 0;
  std::vector<std::string> names;
  std::vector<int> starts;  // where each name starts (0-based)
  std::unordered_map<std::string, int> index_of;
  std::vector<std::string> duplicated;
};

// The first line after skip_lines that is neither blank nor a comment. A UTF-8 byte-order mark
// (spreadsheet exports) is not part of the first name.
MappedHeader ReadMappedHeader(const ColumnMap& map, const std::string& source, std::string_view* rest,
                              int* line_number) {
  if (rest->substr(0, 3) == "\xEF\xBB\xBF") rest->remove_prefix(3);
  TextLine line;
  for (int k = 0; k < map.skip_lines; ++k) {
    if (!internal::NextLine(rest, line_number, &line)) break;
  }
  bool have_header = false;
  while (internal::NextLine(rest, line_number, &line)) {
    if (!IsSkipped(line.text, map)) {
      have_header = true;
      break;
    }
  }
  if (!have_header) throw Error(source + ": no header line (the file is empty after skipped and comment lines)");
  MappedHeader header;
  header.line = line.number;
  std::vector<std::string_view> cells;
  SplitCells(line.text, map, &cells, &header.starts);
  header.names.assign(cells.begin(), cells.end());
  for (size_t k = 0; k < header.names.size(); ++k) {
    if (!header.index_of.emplace(header.names[k], static_cast<int>(k)).second) {
      header.duplicated.push_back(header.names[k]);
    }
  }
  return header;
}

// One CSV column the map refers to, and the values read from it.
struct NeededColumn {
  std::string name;
  int cell = -1;  // index in a row
  const MappedQuantity* quantity = nullptr;
  bool is_time = false;
  std::vector<double> values;  // the time: the stamps' coarse parts
  std::vector<double> fine;    // the time: the stamps' fine parts (internal::TimeStamp)
};

// The columns read for the quantities, each column once even when several quantities share it.
struct MappedColumns {
  std::vector<const MappedQuantity*> quantities;       // time first
  std::vector<NeededColumn> needed;                    // in the order first named
  std::vector<std::vector<size_t>> slots_of_quantity;  // per quantity, per column: index in `needed`
  std::vector<int> row_lines;                          // file line of each row read

  int num_rows() const { return static_cast<int>(row_lines.size()); }
  const std::vector<double>& Values(const MappedQuantity& q, size_t column) const {
    const auto qi = static_cast<size_t>(std::find(quantities.begin(), quantities.end(), &q) - quantities.begin());
    return needed[slots_of_quantity[qi][column]].values;
  }
  // One column in SI units (or the map's command units): raw * scale * unit factor.
  Eigen::VectorXd Scaled(const MappedQuantity& q, size_t column) const {
    const std::vector<double>& v = Values(q, column);
    Eigen::VectorXd out(num_rows());
    for (int i = 0; i < num_rows(); ++i) out[i] = v[i] * q.scale * q.unit_factor;
    return out;
  }
  Eigen::MatrixX3d Vector3(const MappedQuantity& q) const {
    Eigen::MatrixX3d out(num_rows(), 3);
    for (int a = 0; a < 3; ++a) out.col(a) = Scaled(q, a);
    return out;
  }
};

// Time, gyro, acc, the rotor signal, then what else the map gives.
std::vector<const MappedQuantity*> QuantitiesToRead(const ColumnMap& map, const MappedQuantity& rotor) {
  std::vector<const MappedQuantity*> quantities = {&map.time, &map.gyro, &map.acc, &rotor};
  for (const auto* q : {&map.position, &map.quaternion, &map.euler, &map.voltage}) {
    if (*q) quantities.push_back(&**q);
  }
  return quantities;
}

// Every column the quantities name must appear once in the header. Time is parsed unlike the
// others, so it never shares a column with them.
MappedColumns LocateColumns(const std::vector<const MappedQuantity*>& quantities, const MappedHeader& header,
                            const ColumnMap& map, const std::string& source) {
  MappedColumns columns;
  columns.quantities = quantities;
  std::unordered_map<std::string, size_t> needed_of;
  for (size_t qi = 0; qi < quantities.size(); ++qi) {
    const MappedQuantity& q = *quantities[qi];
    std::vector<size_t> slots;
    for (size_t c = 0; c < q.columns.size(); ++c) {
      const std::string& name = q.columns[c];
      const auto found = header.index_of.find(name);
      if (found == header.index_of.end()) {
        throw Error(Located(source, header.line, 0,
                            "no column '" + name + "' (named at " + Where(map.source, q.column_locations[c]) +
                                "); the header has: " + HeaderPreview(header.names)));
      }
      if (std::find(header.duplicated.begin(), header.duplicated.end(), name) != header.duplicated.end()) {
        throw Error(Located(source, header.line, header.starts[found->second] + 1,
                            "column '" + name + "' appears more than once in the header; the map cannot tell which"));
      }
      const bool is_time = qi == 0;
      const auto existing = needed_of.find(name);
      if (existing != needed_of.end() && !(is_time || columns.needed[existing->second].is_time)) {
        slots.push_back(existing->second);
        continue;
      }
      NeededColumn column;
      column.name = name;
      column.cell = found->second;
      column.quantity = &q;
      column.is_time = is_time;
      needed_of.emplace(name, columns.needed.size());
      slots.push_back(columns.needed.size());
      columns.needed.push_back(std::move(column));
    }
    columns.slots_of_quantity.push_back(std::move(slots));
  }
  return columns;
}

// The rows after the header: only the needed cells are parsed, so text columns elsewhere do no
// harm.
void ReadMappedRows(std::string_view rest, int line_number, size_t num_cells, const ColumnMap& map,
                    const std::string& source, MappedColumns* columns) {
  const size_t expected_rows = static_cast<size_t>(std::count(rest.begin(), rest.end(), '\n')) + 1;
  for (NeededColumn& column : columns->needed) {
    column.values.reserve(expected_rows);
    if (column.is_time) column.fine.reserve(expected_rows);
  }
  columns->row_lines.reserve(expected_rows);
  std::vector<std::string_view> cells;
  std::vector<int> starts;
  TextLine line;
  while (internal::NextLine(&rest, &line_number, &line)) {
    if (IsSkipped(line.text, map)) continue;
    SplitCells(line.text, map, &cells, &starts);
    if (cells.size() != num_cells) {
      throw Error(Located(source, line.number, 0,
                          "row has " + std::to_string(cells.size()) + " cells, the header has " +
                              std::to_string(num_cells) + " (truncated or malformed row)"));
    }
    for (NeededColumn& column : columns->needed) {
      const std::string_view cell = cells[column.cell];
      std::optional<internal::TimeStamp> value;
      if (column.is_time)
        value = internal::ParseTimeStamp(cell, column.quantity->scale, column.quantity->unit_factor);
      else if (const std::optional<double> number = internal::ParseFiniteNumber(cell))
        value = internal::TimeStamp{*number};
      if (!value) {
        throw Error(Located(
            source, line.number, starts[column.cell] + 1,
            "column '" + column.name + "' holds '" + std::string(cell.substr(0, 40)) + "', not a finite number"));
      }
      column.values.push_back(value->coarse_s);
      if (column.is_time) column.fine.push_back(value->fine_s);
    }
    columns->row_lines.push_back(line.number);
  }
}

// Wall-clock stamps become offsets from the first (metadata 'time_origin_s'; internal::TimesFromStamps).
Eigen::VectorXd ReadTime(const MappedColumns& columns, const ColumnMap& map, const std::string& source,
                         std::map<std::string, std::string>* metadata) {
  const NeededColumn& time = columns.needed[columns.slots_of_quantity[0][0]];
  std::vector<internal::TimeStamp> stamps(time.values.size());
  for (size_t i = 0; i < stamps.size(); ++i) stamps[i] = {time.values[i], time.fine[i]};
  const Eigen::VectorXd t_s = internal::TimesFromStamps(stamps, metadata);
  if (const std::optional<int> i = internal::FirstNonIncreasingTime(t_s)) {
    throw Error(Located(source, columns.row_lines[*i], 0,
                        "time goes backwards or repeats: column '" + map.time.columns[0] + "' " +
                            std::to_string(t_s[*i]) + " s after " + std::to_string(t_s[*i - 1]) + " s"));
  }
  return t_s;
}

// Commands normalised over their range; speeds in rad/s, which must not be negative.
Eigen::MatrixXd ReadRotorSignal(const MappedColumns& columns, const MappedQuantity& rotor, const ColumnMap& map,
                                const std::string& source) {
  const int n = columns.num_rows();
  const int num_columns = static_cast<int>(rotor.columns.size());
  Eigen::MatrixXd signal(n, num_columns);
  for (int r = 0; r < num_columns; ++r) {
    const std::vector<double>& v = columns.Values(rotor, r);
    for (int i = 0; i < n; ++i) {
      double x = v[i] * rotor.scale;
      if (rotor.is_command) {
        // A command below the range's low end stops the motor: clamp at 0.
        x = std::max(0.0, (x - rotor.range_low) / (rotor.range_high - rotor.range_low));
      } else {
        x *= rotor.unit_factor;
        if (x < 0.0) {
          throw Error(Located(source, columns.row_lines[i], 0,
                              "column '" + rotor.columns[r] + "' holds a negative rotor speed; rotor columns are " +
                                  "|Omega| (map: " + Where(map.source, rotor.column_locations[r]) + ")"));
        }
      }
      signal(i, r) = x;
    }
  }
  return signal;
}

void DescribeRotorSignal(const MappedQuantity& rotor, std::map<std::string, std::string>* metadata) {
  (*metadata)["rotor_signal"] = rotor.is_command ? "command" : "speed";
  (*metadata)["rotor_signal_unit"] = rotor.unit;
  std::string names;
  for (const auto& c : rotor.columns) names += (names.empty() ? "" : ",") + c;
  (*metadata)["rotor_signal_columns"] = names;
}

// Position, and the attitude from the quaternion or the Euler angles, in rotorid's frames.
MocapTrack MocapFromColumns(const MappedColumns& columns, const ColumnMap& map, const std::string& source) {
  const int n = columns.num_rows();
  const Eigen::Matrix3d body_flip = FrameFlip(map.frame == BodyFrame::kFrd);
  const Eigen::Matrix3d world_flip = FrameFlip(map.world_frame == WorldFrame::kNed);
  MocapTrack mocap;
  mocap.position_w_m = columns.Vector3(*map.position) * world_flip;
  mocap.bryant_rad.resize(n, 3);
  if (map.quaternion) {
    const MappedQuantity& quaternion = *map.quaternion;
    const std::vector<double>& qw = columns.Values(quaternion, 0);
    const std::vector<double>& qx = columns.Values(quaternion, 1);
    const std::vector<double>& qy = columns.Values(quaternion, 2);
    const std::vector<double>& qz = columns.Values(quaternion, 3);
    for (int i = 0; i < n; ++i) {
      Eigen::Quaterniond q(qw[i], qx[i], qy[i], qz[i]);
      if (!(q.norm() > 0.5 && q.norm() < 2.0)) {
        throw Error(Located(source, columns.row_lines[i], 0,
                            "the quaternion in columns " + quaternion.columns[0] + ".." + quaternion.columns[3] +
                                " has norm " + std::to_string(q.norm()) + ", not a rotation"));
      }
      const Eigen::Matrix3d r = world_flip * q.normalized().toRotationMatrix() * body_flip;
      mocap.bryant_rad.row(i) = RotationToBryant(r).transpose();
    }
  } else {
    const Eigen::MatrixX3d angles = columns.Vector3(*map.euler);
    const bool flip = map.frame == BodyFrame::kFrd || map.world_frame == WorldFrame::kNed;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d rpy = angles.row(i).transpose();
      const Eigen::Vector3d converted = flip ? RotationToBryant(world_flip * BryantToRotation(rpy) * body_flip) : rpy;
      mocap.bryant_rad.row(i) = converted.transpose();
    }
  }
  return mocap;
}

}  // namespace

FlightLog ParseMappedCsv(std::string_view text, const std::string& source, const ColumnMap& map, int num_rotors,
                         const std::string& rotor_signal) {
  const MappedQuantity* rotor = ChooseRotorSignal(map, rotor_signal, num_rotors);
  std::string_view rest = text;
  int line_number = 0;
  const MappedHeader header = ReadMappedHeader(map, source, &rest, &line_number);
  MappedColumns columns = LocateColumns(QuantitiesToRead(map, *rotor), header, map, source);
  ReadMappedRows(rest, line_number, header.names.size(), map, source, &columns);
  internal::RequireMinFlightSamples(source, columns.num_rows());

  FlightLog log;
  log.source = source;
  log.gravity_mps2 = map.gravity_mps2;
  log.metadata = map.metadata;
  log.metadata["column_map"] = map.source;
  log.t_s = ReadTime(columns, map, source, &log.metadata);
  // Rows are samples: the frame change v' = F v is row' = row F (F symmetric).
  const Eigen::Matrix3d body_flip = FrameFlip(map.frame == BodyFrame::kFrd);
  log.gyro_radps = columns.Vector3(map.gyro) * body_flip;
  log.acc_mps2 = columns.Vector3(map.acc) * body_flip;
  log.rotor_radps = ReadRotorSignal(columns, *rotor, map, source);
  DescribeRotorSignal(*rotor, &log.metadata);
  if (map.position) log.mocap = MocapFromColumns(columns, map, source);
  if (map.voltage) log.voltage_v = columns.Scaled(*map.voltage, 0);
  return log;
}

FlightLog ReadMappedCsv(const std::string& csv_path, const ColumnMap& map, int num_rotors,
                        const std::string& rotor_signal) {
  const std::string text = ReadFile(csv_path);
  return ParseMappedCsv(text, csv_path, map, num_rotors, rotor_signal);
}

}  // namespace rotorid
