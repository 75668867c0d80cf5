#include "rotorid/io/flight_csv.h"

#include <charconv>
#include <cmath>
#include <map>
#include <optional>
#include <string_view>
#include <vector>

#include <fast_float/fast_float.h>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/model/rotation.h"

namespace rotorid {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> SplitCells(std::string_view line) {
  std::vector<std::string_view> cells;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    cells.push_back(Trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return cells;
}

// Column numbers (1-based) where each cell starts, for error messages.
int CellColumn(std::string_view line, size_t cell_index) {
  size_t pos = 0;
  for (size_t k = 0; k < cell_index; ++k) pos = line.find(',', pos) + 1;
  return static_cast<int>(pos) + 1;
}

// The columns INTERFACE.md section 2 defines; any other column is ignored, whatever it holds.
bool IsKnownColumn(const std::string& name) {
  static const char* const kNames[] = {"t",     "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y",  "acc_z",
                                       "pos_x", "pos_y",  "pos_z",  "roll",   "pitch", "yaw",    "qw",
                                       "qx",    "qy",     "qz",     "vel_x",  "vel_y", "vel_z",  "voltage"};
  for (const char* known : kNames)
    if (name == known) return true;
  return name.size() > 6 && name.compare(0, 6, "rotor_") == 0 &&
         name.find_first_not_of("0123456789", 6) == std::string::npos;
}

struct ColumnSet {
  std::map<std::string, int> index;  // name -> cell index
  std::optional<int> Find(const std::string& name) const {
    const auto it = index.find(name);
    if (it == index.end()) return std::nullopt;
    return it->second;
  }
};

}  // namespace

FlightLog ParseFlightCsv(const std::string& text, const std::string& source, int num_rotors) {
  FlightLog log;
  log.source = source;
  std::string_view rest(text);
  int line_number = 0;
  std::optional<ColumnSet> columns;
  int header_line = 0;
  std::string_view header_text;
  size_t num_cells = 0;
  std::vector<std::string> header_names;
  std::vector<std::vector<double>> data;  // per column index (cell index)
  std::vector<bool> known;                 // per cell index: a column rotorid reads

  while (!rest.empty()) {
    const size_t newline = rest.find('\n');
    std::string_view line = rest.substr(0, newline);
    rest = newline == std::string_view::npos ? std::string_view() : rest.substr(newline + 1);
    ++line_number;
    const std::string_view trimmed = Trim(line);
    if (trimmed.empty()) continue;
    if (trimmed.front() == '#') {
      const std::string_view body = Trim(trimmed.substr(1));
      const size_t colon = body.find(':');
      if (colon != std::string_view::npos && colon > 0 && body.substr(0, colon).find(' ') == std::string_view::npos)
        log.metadata[std::string(Trim(body.substr(0, colon)))] = std::string(Trim(body.substr(colon + 1)));
      continue;
    }
    if (!columns) {
      columns.emplace();
      header_line = line_number;
      header_text = line;
      const auto names = SplitCells(line);
      num_cells = names.size();
      for (size_t k = 0; k < names.size(); ++k) {
        const std::string name(names[k]);
        header_names.push_back(name);
        known.push_back(IsKnownColumn(name));
        if (name.empty()) throw Error(Located(source, line_number, CellColumn(line, k), "empty column name in header"));
        if (!columns->index.emplace(name, static_cast<int>(k)).second)
          throw Error(Located(source, line_number, CellColumn(line, k), "duplicate column '" + name + "'"));
      }
      data.resize(num_cells);
      continue;
    }
    const auto cells = SplitCells(line);
    if (cells.size() != num_cells) {
      throw Error(Located(source, line_number, 0,
                          "row has " + std::to_string(cells.size()) + " cells, the header has " +
                              std::to_string(num_cells) + " (truncated or malformed row)"));
    }
    for (size_t k = 0; k < cells.size(); ++k) {
      if (!known[k]) continue;
      double value = 0.0;
      const char* first = cells[k].data();
      const char* last = first + cells[k].size();
      const auto result = fast_float::from_chars(first, last, value);
      if (cells[k].empty() || result.ec != std::errc() || result.ptr != last) {
        throw Error(Located(source, line_number, CellColumn(line, k),
                            "column '" + header_names[k] + "' is not a number: '" + std::string(cells[k]) + "'"));
      }
      if (!std::isfinite(value)) {
        throw Error(Located(source, line_number, CellColumn(line, k),
                            "column '" + header_names[k] + "' holds '" + std::string(cells[k]) + "', not a finite number"));
      }
      data[k].push_back(value);
    }
  }
  if (!columns) throw Error(source + ": empty file: no header line and no samples");

  auto require = [&](const std::string& name) -> int {
    const auto k = columns->Find(name);
    if (!k) throw Error(Located(source, header_line, 0, "missing required column '" + name + "'"));
    return *k;
  };
  const int t_col = require("t");
  for (const char* name : {"gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"}) require(name);
  const int n = static_cast<int>(data[t_col].size());
  if (n < kMinFlightSamples)
    throw Error(source + ": too few samples (" + std::to_string(n) + "); at least " +
                std::to_string(kMinFlightSamples) + " are needed");

  auto column = [&](int k) { return Eigen::Map<const Eigen::VectorXd>(data[k].data(), n); };
  log.t_s = column(t_col);
  // Data rows start after the header; blank and comment lines are rare, so locate rows by scanning.
  for (int i = 1; i < n; ++i) {
    if (!(log.t_s[i] > log.t_s[i - 1])) {
      // Find the file line of data row i for the message.
      int row = -1, line_no = 0;
      std::string_view scan(text);
      while (!scan.empty()) {
        const size_t nl = scan.find('\n');
        const std::string_view l = Trim(scan.substr(0, nl));
        scan = nl == std::string_view::npos ? std::string_view() : scan.substr(nl + 1);
        ++line_no;
        if (line_no <= header_line || l.empty() || l.front() == '#') continue;
        if (++row == i) break;
      }
      throw Error(Located(source, line_no, 1,
                          "time goes backwards or repeats: t = " + std::to_string(log.t_s[i]) + " after " +
                              std::to_string(log.t_s[i - 1])));
    }
  }
  const char* axes[3] = {"x", "y", "z"};
  log.gyro_radps.resize(n, 3);
  log.acc_mps2.resize(n, 3);
  for (int a = 0; a < 3; ++a) {
    log.gyro_radps.col(a) = column(require(std::string("gyro_") + axes[a]));
    log.acc_mps2.col(a) = column(require(std::string("acc_") + axes[a]));
  }
  if (num_rotors < 0) {
    num_rotors = 0;
    while (columns->Find("rotor_" + std::to_string(num_rotors + 1))) ++num_rotors;
    if (num_rotors == 0) throw Error(Located(source, header_line, 0, "missing required column 'rotor_1'"));
  }
  // A rotor the vehicle file leaves out would be dropped silently.
  if (const auto extra = columns->Find("rotor_" + std::to_string(num_rotors + 1)))
    throw Error(Located(source, header_line, CellColumn(header_text, *extra),
                        "the log has column 'rotor_" + std::to_string(num_rotors + 1) + "' but the vehicle file has " +
                            std::to_string(num_rotors) + " rotors: give every rotor in the vehicle file"));
  std::vector<int> rotor_columns;  // all located before any allocation that scales with the count
  for (int r = 0; r < num_rotors; ++r) rotor_columns.push_back(require("rotor_" + std::to_string(r + 1)));
  log.rotor_radps.resize(n, num_rotors);
  for (int r = 0; r < num_rotors; ++r) {
    const std::string name = "rotor_" + std::to_string(r + 1);
    log.rotor_radps.col(r) = column(rotor_columns[r]);
    if ((log.rotor_radps.col(r).array() < 0.0).any())
      throw Error(Located(source, header_line, 0, "column '" + name + "' has negative rotor speeds; it must hold |Omega| in rad/s"));
  }
  if (columns->Find("pos_x")) {
    MocapTrack mocap;
    mocap.position_w_m.resize(n, 3);
    for (int a = 0; a < 3; ++a) mocap.position_w_m.col(a) = column(require(std::string("pos_") + axes[a]));
    mocap.bryant_rad.resize(n, 3);
    if (columns->Find("roll")) {
      mocap.bryant_rad.col(0) = column(require("roll"));
      mocap.bryant_rad.col(1) = column(require("pitch"));
      mocap.bryant_rad.col(2) = column(require("yaw"));
    } else if (columns->Find("qw")) {
      const auto qw = column(require("qw")), qx = column(require("qx")), qy = column(require("qy")),
                 qz = column(require("qz"));
      for (int i = 0; i < n; ++i) {
        Eigen::Quaterniond q(qw[i], qx[i], qy[i], qz[i]);
        if (!(q.norm() > 0.5)) throw Error(source + ": quaternion of data row " + std::to_string(i + 1) + " is not a rotation");
        mocap.bryant_rad.row(i) = RotationToBryant(q.normalized().toRotationMatrix()).transpose();
      }
    } else {
      throw Error(Located(source, header_line, 0, "pos_x..z given without roll,pitch,yaw or qw,qx,qy,qz"));
    }
    if (columns->Find("vel_x")) {
      Eigen::MatrixX3d velocity(n, 3);
      for (int a = 0; a < 3; ++a) velocity.col(a) = column(require(std::string("vel_") + axes[a]));
      mocap.velocity_w_mps = std::move(velocity);
    }
    log.mocap = std::move(mocap);
  } else if (const auto k = columns->Find("vel_x")) {
    throw Error(Located(source, header_line, CellColumn(header_text, *k),
                        "vel_x..z (world frame) need the pose (pos_x..z with roll,pitch,yaw or qw,qx,qy,qz) to be "
                        "turned into the body frame"));
  }
  if (const auto k = columns->Find("voltage")) log.voltage_v = column(*k);
  if (const auto it = log.metadata.find("gravity"); it != log.metadata.end()) {
    double g = 0.0;
    const auto result = fast_float::from_chars(it->second.data(), it->second.data() + it->second.size(), g);
    if (result.ec != std::errc() || !(g > 0.0) || !std::isfinite(g))
      throw Error(source + ": metadata 'gravity' must be a positive number, got '" + it->second + "'");
    log.gravity_mps2 = g;
  }
  return log;
}

FlightLog ReadFlightCsv(const std::string& path, int num_rotors) { return ParseFlightCsv(ReadFile(path), path, num_rotors); }

namespace {
void AppendNumber(std::string* out, double value, int precision) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::general, precision);
  out->append(buffer, result.ptr);
}
}  // namespace

std::string FlightLogToCsv(const FlightLog& log) {
  std::string out = "# rotorid flight log v1\n";
  for (const auto& [key, value] : log.metadata) out += "# " + key + ": " + value + "\n";
  out += "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z";
  for (int r = 0; r < log.num_rotors(); ++r) out += ",rotor_" + std::to_string(r + 1);
  if (log.mocap) out += ",pos_x,pos_y,pos_z,roll,pitch,yaw";
  if (log.mocap && log.mocap->velocity_w_mps) out += ",vel_x,vel_y,vel_z";
  if (log.voltage_v) out += ",voltage";
  out += "\n";
  out.reserve(out.size() + static_cast<size_t>(log.num_samples()) * (16 + 12 * (6 + log.num_rotors())));
  for (int i = 0; i < log.num_samples(); ++i) {
    AppendNumber(&out, log.t_s[i], 10);
    auto add = [&](double v) {
      out += ',';
      AppendNumber(&out, v, 9);
    };
    for (int a = 0; a < 3; ++a) add(log.gyro_radps(i, a));
    for (int a = 0; a < 3; ++a) add(log.acc_mps2(i, a));
    for (int r = 0; r < log.num_rotors(); ++r) add(log.rotor_radps(i, r));
    if (log.mocap) {
      for (int a = 0; a < 3; ++a) add(log.mocap->position_w_m(i, a));
      for (int a = 0; a < 3; ++a) add(log.mocap->bryant_rad(i, a));
      if (log.mocap->velocity_w_mps)
        for (int a = 0; a < 3; ++a) add((*log.mocap->velocity_w_mps)(i, a));
    }
    if (log.voltage_v) add((*log.voltage_v)[i]);
    out += '\n';
  }
  return out;
}

void WriteFlightCsv(const std::string& path, const FlightLog& log) { WriteFileAtomically(path, FlightLogToCsv(log)); }

}  // namespace rotorid
