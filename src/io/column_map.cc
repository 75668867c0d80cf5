#include "rotorid/io/column_map.h"

#include <fast_float/fast_float.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "io/yaml_fields.h"
#include "rotorid/core/error.h"
#include "rotorid/core/units.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/flight_csv.h"
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

}  // namespace

ColumnMap ParseColumnMap(const std::string& text, const std::string& source) {
  const YAML::Node root = internal::LoadYaml(text, source);
  if (!root.IsMap()) throw Error(source + ": a column map must be a YAML mapping with time, gyro, acc and rotors");

  ColumnMap map;
  map.source = source;
  // Scalars first: gravity feeds the unit g of acc.
  std::map<std::string, std::pair<YAML::Node, YAML::Node>> entries;  // key -> (key node, value node)
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
    if (entries.count(key)) internal::FailAt(source, it->first, "key '" + key + "' appears twice");
    entries.emplace(key, std::make_pair(it->first, it->second));
  }
  auto find = [&](const std::string& key) -> const std::pair<YAML::Node, YAML::Node>* {
    const auto it = entries.find(key);
    return it == entries.end() ? nullptr : &it->second;
  };

  if (const auto* g = find("gravity")) {
    map.gravity_mps2 = internal::ReadYamlNumber(source, g->second, "gravity");
    if (!(map.gravity_mps2 > 0.0)) internal::FailAt(source, g->second, "gravity must be positive (m/s^2)");
  }
  if (const auto* f = find("frame")) {
    const std::string frame = ReadString(source, f->second, "frame");
    if (frame == "flu") {
      map.frame = BodyFrame::kFlu;
    } else if (frame == "frd") {
      map.frame = BodyFrame::kFrd;
    } else {
      internal::FailAt(source, f->second, "frame must be flu or frd, got '" + frame + "'");
    }
  }
  map.world_frame = map.frame == BodyFrame::kFrd ? WorldFrame::kNed : WorldFrame::kZUp;
  if (const auto* f = find("world_frame")) {
    const std::string frame = ReadString(source, f->second, "world_frame");
    if (frame == "zup" || frame == "enu" || frame == "nwu") {
      map.world_frame = WorldFrame::kZUp;
    } else if (frame == "ned") {
      map.world_frame = WorldFrame::kNed;
    } else {
      internal::FailAt(source, f->second, "world_frame must be zup (also: enu, nwu) or ned, got '" + frame + "'");
    }
  }
  if (const auto* d = find("delimiter")) {
    const std::string delimiter = ReadString(source, d->second, "delimiter");
    if (delimiter == "whitespace") {
      map.whitespace_delimited = true;
    } else if (delimiter == "tab") {
      map.delimiter = '\t';
    } else if (delimiter.size() == 1 && delimiter != "\"" && delimiter != "\n" && delimiter != "\r") {
      map.delimiter = delimiter[0];
    } else {
      internal::FailAt(source, d->second,
                       "delimiter must be one character (e.g. \",\", \";\", \"\\t\"), tab or whitespace");
    }
  }
  if (const auto* c = find("comment")) {
    map.comment = c->second.IsNull() ? "" : ReadString(source, c->second, "comment");
  }
  if (const auto* s = find("skip_lines")) {
    const double lines = internal::ReadYamlNumber(source, s->second, "skip_lines");
    if (lines < 0 || lines > 1e6 || lines != std::floor(lines)) {
      internal::FailAt(source, s->second, "skip_lines must be a whole number >= 0");
    }
    map.skip_lines = static_cast<int>(lines);
  }
  if (const auto* m = find("metadata")) {
    if (!m->second.IsMap()) internal::FailAt(source, m->second, "metadata must be a mapping of key: value");
    for (auto it = m->second.begin(); it != m->second.end(); ++it) {
      map.metadata[ReadString(source, it->first, "metadata key")] = ReadString(source, it->second, "metadata value");
    }
  }

  const QuantitySpec kTime{"time", 1, &kTimeUnits, "{column: t, unit: s}"};
  const QuantitySpec kGyro{"gyro", 3, &kGyroUnits, "{columns: [gx, gy, gz], unit: rad/s}"};
  const QuantitySpec kAcc{"acc", 3, &kAccUnits, "{columns: [ax, ay, az], unit: m/s^2}"};
  const QuantitySpec kRotors{"rotors", -1, &kRotorUnits, "{columns: [m1, m2, m3, m4], unit: rpm}"};
  const QuantitySpec kCommands{"rotor_commands", -1, &kCommandUnits, "{columns: [m1, m2, m3, m4], unit: pwm}"};
  const QuantitySpec kPosition{"position", 3, &kPositionUnits, "{columns: [px, py, pz], unit: m}"};
  const QuantitySpec kQuaternion{"quaternion", 4, nullptr, "{columns: [qw, qx, qy, qz]}"};
  const QuantitySpec kEuler{"euler", 3, &kAngleUnits, "{columns: [roll, pitch, yaw], unit: deg}"};
  const QuantitySpec kVoltage{"voltage", 1, &kVoltageUnits, "{column: vbat, unit: V}"};

  auto required = [&](const QuantitySpec& spec) {
    const auto* entry = find(spec.key);
    if (!entry) throw Error(source + ": missing '" + spec.key + "', e.g. " + spec.key + ": " + spec.example);
    return ParseQuantity(source, entry->first, entry->second, spec, map.gravity_mps2);
  };
  auto optional = [&](const QuantitySpec& spec) -> std::optional<MappedQuantity> {
    const auto* entry = find(spec.key);
    if (!entry) return std::nullopt;
    return ParseQuantity(source, entry->first, entry->second, spec, map.gravity_mps2);
  };
  map.time = required(kTime);
  map.gyro = required(kGyro);
  map.acc = required(kAcc);
  map.rotors = optional(kRotors);
  map.rotor_commands = optional(kCommands);
  map.position = optional(kPosition);
  map.quaternion = optional(kQuaternion);
  map.euler = optional(kEuler);
  map.voltage = optional(kVoltage);

  if (!map.rotors && !map.rotor_commands) {
    throw Error(source + ": missing 'rotors', e.g. rotors: " + kRotors.example);
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
  return map;
}

ColumnMap ReadColumnMap(const std::string& path) { return ParseColumnMap(ReadFile(path), path); }

// ---- The CSV ----

namespace {

std::string_view TrimSpaces(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

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

struct Line {
  std::string_view text;
  int number;  // 1-based
};

// The next line of `rest` (without '\n' and trailing '\r').
bool NextLine(std::string_view* rest, int* number, Line* line) {
  if (rest->empty()) return false;
  const size_t newline = rest->find('\n');
  std::string_view text = rest->substr(0, newline);
  *rest = newline == std::string_view::npos ? std::string_view() : rest->substr(newline + 1);
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  *line = {text, ++*number};
  return true;
}

bool IsSkipped(std::string_view text, const ColumnMap& map) {
  const std::string_view trimmed = TrimSpaces(text);
  if (trimmed.empty()) return true;
  return !map.comment.empty() && trimmed.substr(0, map.comment.size()) == map.comment;
}

// One CSV column the map refers to, and the values read from it.
struct NeededColumn {
  std::string name;
  int cell = -1;  // index in a row
  const MappedQuantity* quantity = nullptr;
  MapLocation map_location;
  bool is_time = false;
  std::vector<double> values;
};

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

// Time cells in integer units (us, ns) can exceed double's 53 bits; read them as integers and
// split whole seconds from the fraction so that no precision is lost before scaling.
bool ParseTime(std::string_view cell, const MappedQuantity& q, double* seconds) {
  if (q.scale == 1.0 && q.unit_factor < 1.0) {
    int64_t ticks = 0;
    const auto r = std::from_chars(cell.data(), cell.data() + cell.size(), ticks);
    if (r.ec == std::errc() && r.ptr == cell.data() + cell.size()) {
      const auto per_second = static_cast<int64_t>(std::llround(1.0 / q.unit_factor));
      *seconds = static_cast<double>(ticks / per_second) + static_cast<double>(ticks % per_second) * q.unit_factor;
      return true;
    }
  }
  double value = 0.0;
  const auto r = fast_float::from_chars(cell.data(), cell.data() + cell.size(), value);
  if (cell.empty() || r.ec != std::errc() || r.ptr != cell.data() + cell.size() || !std::isfinite(value)) return false;
  *seconds = value * q.scale * q.unit_factor;
  return true;
}

Eigen::Matrix3d FrameFlip(bool flip) {
  return flip ? Eigen::Vector3d(1, -1, -1).asDiagonal().toDenseMatrix() : Eigen::Matrix3d::Identity();
}

}  // namespace

FlightLog ParseMappedCsv(std::string_view text, const std::string& source, const ColumnMap& map, int num_rotors,
                         const std::string& rotor_signal) {
  if (rotor_signal != "auto" && rotor_signal != "rpm" && rotor_signal != "command") {
    throw Error("rotor signal must be auto, rpm or command, got '" + rotor_signal + "'");
  }
  // Which rotor signal: speed when available (unless commands are asked for), else the command.
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

  // Header. A UTF-8 byte-order mark (spreadsheet exports) is not part of the first name.
  std::string_view rest = text;
  if (rest.substr(0, 3) == "\xEF\xBB\xBF") rest.remove_prefix(3);
  int line_number = 0;
  Line line;
  for (int k = 0; k < map.skip_lines; ++k) {
    if (!NextLine(&rest, &line_number, &line)) break;
  }
  bool have_header = false;
  while (NextLine(&rest, &line_number, &line)) {
    if (!IsSkipped(line.text, map)) {
      have_header = true;
      break;
    }
  }
  if (!have_header) throw Error(source + ": no header line (the file is empty after skipped and comment lines)");
  const int header_line = line.number;
  std::vector<std::string_view> cells;
  std::vector<int> starts;
  SplitCells(line.text, map, &cells, &starts);
  std::vector<std::string> header(cells.begin(), cells.end());
  std::unordered_map<std::string, int> index_of;
  std::vector<std::string> duplicated;
  for (size_t k = 0; k < header.size(); ++k) {
    if (!index_of.emplace(header[k], static_cast<int>(k)).second) duplicated.push_back(header[k]);
  }

  // The columns the map needs, each read once even when several quantities share it.
  std::vector<NeededColumn> needed;
  std::unordered_map<std::string, size_t> needed_of;
  std::vector<std::vector<size_t>> slots_of_quantity;  // per quantity in `quantities`, per column
  std::vector<const MappedQuantity*> quantities = {&map.time, &map.gyro, &map.acc, rotor};
  for (const auto* q : {&map.position, &map.quaternion, &map.euler, &map.voltage}) {
    if (*q) quantities.push_back(&**q);
  }
  for (size_t qi = 0; qi < quantities.size(); ++qi) {
    const MappedQuantity& q = *quantities[qi];
    std::vector<size_t> slots;
    for (size_t c = 0; c < q.columns.size(); ++c) {
      const std::string& name = q.columns[c];
      const auto found = index_of.find(name);
      if (found == index_of.end()) {
        throw Error(Located(source, header_line, 0,
                            "no column '" + name + "' (named at " + Where(map.source, q.column_locations[c]) +
                                "); the header has: " + HeaderPreview(header)));
      }
      if (std::find(duplicated.begin(), duplicated.end(), name) != duplicated.end()) {
        throw Error(Located(source, header_line, starts[found->second] + 1,
                            "column '" + name + "' appears more than once in the header; the map cannot tell which"));
      }
      const bool is_time = qi == 0;
      const auto existing = needed_of.find(name);
      if (existing != needed_of.end() && !(is_time || needed[existing->second].is_time)) {
        slots.push_back(existing->second);
        continue;
      }
      NeededColumn column;
      column.name = name;
      column.cell = found->second;
      column.quantity = &q;
      column.map_location = q.column_locations[c];
      column.is_time = is_time;
      needed_of.emplace(name, needed.size());
      slots.push_back(needed.size());
      needed.push_back(std::move(column));
    }
    slots_of_quantity.push_back(std::move(slots));
  }

  // Rows: only the needed cells are parsed, so text columns elsewhere do no harm.
  const size_t expected_rows = static_cast<size_t>(std::count(rest.begin(), rest.end(), '\n')) + 1;
  for (NeededColumn& column : needed) column.values.reserve(expected_rows);
  std::vector<int> row_lines;
  row_lines.reserve(expected_rows);
  while (NextLine(&rest, &line_number, &line)) {
    if (IsSkipped(line.text, map)) continue;
    SplitCells(line.text, map, &cells, &starts);
    if (cells.size() != header.size()) {
      throw Error(Located(source, line.number, 0,
                          "row has " + std::to_string(cells.size()) + " cells, the header has " +
                              std::to_string(header.size()) + " (truncated or malformed row)"));
    }
    for (NeededColumn& column : needed) {
      const std::string_view cell = cells[column.cell];
      double value = 0.0;
      bool ok;
      if (column.is_time) {
        ok = ParseTime(cell, *column.quantity, &value);
      } else {
        const auto r = fast_float::from_chars(cell.data(), cell.data() + cell.size(), value);
        ok = !cell.empty() && r.ec == std::errc() && r.ptr == cell.data() + cell.size() && std::isfinite(value);
      }
      if (!ok) {
        throw Error(Located(
            source, line.number, starts[column.cell] + 1,
            "column '" + column.name + "' holds '" + std::string(cell.substr(0, 40)) + "', not a finite number"));
      }
      column.values.push_back(value);
    }
    row_lines.push_back(line.number);
  }
  const int n = static_cast<int>(row_lines.size());
  if (n < kMinFlightSamples) {
    throw Error(source + ": too few samples (" + std::to_string(n) + "); at least " +
                std::to_string(kMinFlightSamples) + " are needed");
  }

  FlightLog log;
  log.source = source;
  log.gravity_mps2 = map.gravity_mps2;
  log.metadata = map.metadata;
  log.metadata["column_map"] = map.source;
  auto values = [&](size_t qi, size_t c) -> const std::vector<double>& {
    return needed[slots_of_quantity[qi][c]].values;
  };

  log.t_s = Eigen::Map<const Eigen::VectorXd>(values(0, 0).data(), n);
  for (int i = 1; i < n; ++i) {
    if (!(log.t_s[i] > log.t_s[i - 1])) {
      throw Error(Located(source, row_lines[i], 0,
                          "time goes backwards or repeats: column '" + map.time.columns[0] + "' " +
                              std::to_string(log.t_s[i]) + " s after " + std::to_string(log.t_s[i - 1]) + " s"));
    }
  }

  // Vectors in the map's frames; converted to rotorid's (FLU body, z-up world) below.
  auto vector3 = [&](size_t qi) {
    const MappedQuantity& q = *quantities[qi];
    Eigen::MatrixX3d out(n, 3);
    for (int a = 0; a < 3; ++a) {
      const auto& v = values(qi, a);
      for (int i = 0; i < n; ++i) out(i, a) = v[i] * q.scale * q.unit_factor;
    }
    return out;
  };
  const Eigen::Matrix3d body_flip = FrameFlip(map.frame == BodyFrame::kFrd);
  const Eigen::Matrix3d world_flip = FrameFlip(map.world_frame == WorldFrame::kNed);
  log.gyro_radps = vector3(1) * body_flip;  // rows are samples: v' = F v  <=>  row' = row F (F symmetric)
  log.acc_mps2 = vector3(2) * body_flip;

  const int num_columns = static_cast<int>(rotor->columns.size());
  log.rotor_radps.resize(n, num_columns);
  for (int r = 0; r < num_columns; ++r) {
    const auto& v = values(3, r);
    for (int i = 0; i < n; ++i) {
      double x = v[i] * rotor->scale;
      if (rotor->is_command) {
        // A command below the range's low end stops the motor: clamp at 0.
        x = std::max(0.0, (x - rotor->range_low) / (rotor->range_high - rotor->range_low));
      } else {
        x *= rotor->unit_factor;
        if (x < 0.0) {
          throw Error(Located(source, row_lines[i], 0,
                              "column '" + rotor->columns[r] + "' holds a negative rotor speed; rotor columns are " +
                                  "|Omega| (map: " + Where(map.source, rotor->column_locations[r]) + ")"));
        }
      }
      log.rotor_radps(i, r) = x;
    }
  }
  log.metadata["rotor_signal"] = rotor->is_command ? "command" : "speed";
  log.metadata["rotor_signal_unit"] = rotor->unit;
  log.metadata["rotor_signal_columns"] = [&] {
    std::string s;
    for (const auto& c : rotor->columns) s += (s.empty() ? "" : ",") + c;
    return s;
  }();

  size_t qi = 4;
  if (map.position) {
    MocapTrack mocap;
    mocap.position_w_m = vector3(qi++) * world_flip;
    mocap.bryant_rad.resize(n, 3);
    if (map.quaternion) {
      const size_t q_index = qi++;
      for (int i = 0; i < n; ++i) {
        Eigen::Quaterniond q(values(q_index, 0)[i], values(q_index, 1)[i], values(q_index, 2)[i],
                             values(q_index, 3)[i]);
        if (!(q.norm() > 0.5 && q.norm() < 2.0)) {
          throw Error(Located(source, row_lines[i], 0,
                              "the quaternion in columns " + map.quaternion->columns[0] + ".." +
                                  map.quaternion->columns[3] + " has norm " + std::to_string(q.norm()) +
                                  ", not a rotation"));
        }
        const Eigen::Matrix3d r = world_flip * q.normalized().toRotationMatrix() * body_flip;
        mocap.bryant_rad.row(i) = RotationToBryant(r).transpose();
      }
    } else {
      const Eigen::MatrixX3d angles = vector3(qi++);
      const bool flip = map.frame == BodyFrame::kFrd || map.world_frame == WorldFrame::kNed;
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d rpy = angles.row(i).transpose();
        const Eigen::Vector3d converted = flip ? RotationToBryant(world_flip * BryantToRotation(rpy) * body_flip) : rpy;
        mocap.bryant_rad.row(i) = converted.transpose();
      }
    }
    log.mocap = std::move(mocap);
  }
  if (map.voltage) {
    const auto& v = values(qi, 0);
    Eigen::VectorXd volts(n);
    for (int i = 0; i < n; ++i) volts[i] = v[i] * map.voltage->scale * map.voltage->unit_factor;
    log.voltage_v = std::move(volts);
  }
  return log;
}

FlightLog ReadMappedCsv(const std::string& csv_path, const ColumnMap& map, int num_rotors,
                        const std::string& rotor_signal) {
  const std::string text = ReadFile(csv_path);
  return ParseMappedCsv(text, csv_path, map, num_rotors, rotor_signal);
}

}  // namespace rotorid
