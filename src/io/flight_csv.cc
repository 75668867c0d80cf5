#include "rotorid/io/flight_csv.h"

#include <fast_float/fast_float.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <exception>
#include <map>
#include <optional>
#include <string_view>
#include <vector>

#include "core/parallel_for.h"
#include "io/csv_text.h"
#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/model/rotation.h"

namespace rotorid {
namespace {

using internal::TrimSpaces;

// Spreadsheets quote cells ("t","gyro_x"; "0.01"): the quotes are not part of the value.
std::string_view Unquoted(std::string_view cell) {
  return cell.size() >= 2 && cell.front() == '"' && cell.back() == '"' ? cell.substr(1, cell.size() - 2) : cell;
}

std::vector<std::string_view> SplitCells(std::string_view line) {
  std::vector<std::string_view> cells;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    cells.push_back(Unquoted(
        TrimSpaces(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start))));
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
  static const char* const kNames[] = {"t",     "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z",
                                       "pos_x", "pos_y",  "pos_z",  "roll",   "pitch", "yaw",   "qw",
                                       "qx",    "qy",     "qz",     "vel_x",  "vel_y", "vel_z", "voltage"};
  for (const char* known : kNames)
    if (name == known) return true;
  return name.size() > 6 && name.compare(0, 6, "rotor_") == 0 &&
         name.find_first_not_of("0123456789", 6) == std::string::npos;
}

// The rows of a stretch of the file: the values of every column rotorid reads, and the metadata
// of the comments among them.
struct TableRows {
  std::vector<std::vector<double>> data;  // per cell; empty for ignored columns (the time: coarse parts)
  std::vector<double> time_fine;          // the time stamps' fine parts (internal::TimeStamp)
  std::vector<int> row_lines;             // file line of each data row
  std::map<std::string, std::string> metadata;
};

// The file as read: metadata, header, and the values of every column rotorid reads.
struct FlightTable {
  std::string source;
  std::map<std::string, std::string> metadata;
  bool has_header = false;
  int header_line = 0;
  std::string_view header_text;
  std::vector<std::string> names;    // per cell
  std::vector<bool> known;           // per cell: a column rotorid reads
  std::map<std::string, int> index;  // name -> cell
  int time_cell = -1;                // the cell of 't'
  std::vector<TableRows> parts;      // the rows, in file order, as the stretches read them

  std::optional<int> Find(const std::string& name) const {
    const auto it = index.find(name);
    if (it == index.end()) return std::nullopt;
    return it->second;
  }
  int Require(const std::string& name) const {
    const auto k = Find(name);
    if (!k) throw Error(Located(source, header_line, 0, "missing required column '" + name + "'"));
    return *k;
  }
  Eigen::Index num_rows() const {
    size_t rows = 0;
    for (const TableRows& part : parts) rows += part.row_lines.size();
    return static_cast<Eigen::Index>(rows);
  }
  int RowLine(Eigen::Index row) const {
    for (const TableRows& part : parts) {
      if (row < static_cast<Eigen::Index>(part.row_lines.size())) return part.row_lines[static_cast<size_t>(row)];
      row -= static_cast<Eigen::Index>(part.row_lines.size());
    }
    return 0;
  }
  std::vector<internal::TimeStamp> TimeStamps() const {
    std::vector<internal::TimeStamp> stamps;
    stamps.reserve(static_cast<size_t>(num_rows()));
    for (const TableRows& part : parts)
      for (size_t i = 0; i < part.time_fine.size(); ++i)
        stamps.push_back({part.data[static_cast<size_t>(time_cell)][i], part.time_fine[i]});
    return stamps;
  }
  // The parts' values joined (no joined copy of every column is kept: a 1 h log's are 60 MB).
  Eigen::VectorXd Column(int cell) const {
    Eigen::VectorXd column(num_rows());
    Eigen::Index row = 0;
    for (const TableRows& part : parts) {
      const std::vector<double>& values = part.data[static_cast<size_t>(cell)];
      column.segment(row, static_cast<Eigen::Index>(values.size())) =
          Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
      row += static_cast<Eigen::Index>(values.size());
    }
    return column;
  }
};

// "# key: value" (key without spaces) is metadata; other comments say nothing.
void ReadCommentLine(std::string_view trimmed, std::map<std::string, std::string>* metadata) {
  const std::string_view body = TrimSpaces(trimmed.substr(1));
  const size_t colon = body.find(':');
  if (colon != std::string_view::npos && colon > 0 && body.substr(0, colon).find(' ') == std::string_view::npos)
    (*metadata)[std::string(TrimSpaces(body.substr(0, colon)))] = std::string(TrimSpaces(body.substr(colon + 1)));
}

void ReadHeader(const internal::TextLine& line, FlightTable* table) {
  table->has_header = true;
  table->header_line = line.number;
  table->header_text = line.text;
  const auto names = SplitCells(line.text);
  // Another tool's separator: one cell where a dozen were expected.
  const std::pair<char, const char*> separators[] = {{';', "';'"}, {'\t', "tab"}, {' ', "whitespace"}};
  for (const auto& [separator, delimiter] : separators)
    if (names.size() == 1 && names[0].find(separator) != std::string_view::npos)
      throw Error(Located(table->source, line.number, 0,
                          std::string("the header is not separated by commas but by ") + delimiter +
                              ": convert the file, or read it through a column map with delimiter: " + delimiter +
                              " (docs/input_formats.md)"));
  for (size_t k = 0; k < names.size(); ++k) {
    const std::string name(names[k]);
    table->names.push_back(name);
    table->known.push_back(IsKnownColumn(name));
    if (name.empty())
      throw Error(Located(table->source, line.number, CellColumn(line.text, k), "empty column name in header"));
    if (!table->index.emplace(name, static_cast<int>(k)).second)
      throw Error(Located(table->source, line.number, CellColumn(line.text, k), "duplicate column '" + name + "'"));
    if (name == "t") table->time_cell = static_cast<int>(k);
  }
}

// The time stamp of a row, split as internal::TimeStamp.
void ReadTimeCell(const internal::TextLine& line, const FlightTable& table, size_t k, std::string_view raw,
                  TableRows* rows) {
  const std::string_view cell = Unquoted(TrimSpaces(raw));
  const std::optional<internal::TimeStamp> stamp = internal::ParseTimeStamp(cell, 1.0, 1.0);
  if (!stamp)
    throw Error(Located(table.source, line.number, CellColumn(line.text, k),
                        internal::ParseNumber(cell)
                            ? "column 't' holds '" + std::string(cell) + "', not a finite number"
                            : "column 't' is not a number: '" + std::string(cell) + "'"));
  rows->data[k].push_back(stamp->coarse_s);
  rows->time_fine.push_back(stamp->fine_s);
}

// Only the columns rotorid reads must hold numbers. The cells are taken off the line one by one
// (no list of cells per row: a 1 h log has 720k rows).
void ReadRow(const internal::TextLine& line, const FlightTable& table, TableRows* rows) {
  const size_t cells = static_cast<size_t>(std::count(line.text.begin(), line.text.end(), ',')) + 1;
  if (cells != table.names.size()) {
    throw Error(Located(table.source, line.number, 0,
                        "row has " + std::to_string(cells) + " cells, the header has " +
                            std::to_string(table.names.size()) + " (truncated or malformed row)"));
  }
  std::string_view rest = line.text;
  for (size_t k = 0; k < cells; ++k) {
    const size_t comma = rest.find(',');
    const std::string_view raw = rest.substr(0, comma);
    rest.remove_prefix(comma == std::string_view::npos ? rest.size() : comma + 1);
    if (!table.known[k]) continue;
    if (static_cast<int>(k) == table.time_cell) {
      ReadTimeCell(line, table, k, raw, rows);
      continue;
    }
    // Most cells are a bare finite number: parsed in place, without trimming or the checks below.
    double number = 0.0;
    const auto parsed = fast_float::from_chars(raw.data(), raw.data() + raw.size(), number);
    if (parsed.ec == std::errc() && parsed.ptr == raw.data() + raw.size() && !raw.empty() && std::isfinite(number)) {
      rows->data[k].push_back(number);
      continue;
    }
    const std::string_view cell = Unquoted(TrimSpaces(raw));
    const std::optional<double> value = internal::ParseNumber(cell);
    if (!value) {
      throw Error(Located(table.source, line.number, CellColumn(line.text, k),
                          "column '" + table.names[k] + "' is not a number: '" + std::string(cell) + "'"));
    }
    if (!std::isfinite(*value)) {
      throw Error(Located(table.source, line.number, CellColumn(line.text, k),
                          "column '" + table.names[k] + "' holds '" + std::string(cell) + "', not a finite number"));
    }
    rows->data[k].push_back(*value);
  }
  rows->row_lines.push_back(line.number);
}

// Room for `lines` rows in every column rotorid reads: no reallocation while the columns fill.
TableRows ReserveRows(const FlightTable& table, size_t lines) {
  TableRows rows;
  rows.data.resize(table.names.size());
  rows.row_lines.reserve(lines);
  rows.time_fine.reserve(lines);
  for (size_t k = 0; k < rows.data.size(); ++k)
    if (table.known[k]) rows.data[k].reserve(lines);
  return rows;
}

// The rows of `text`, whose line before the first is `line_number`, into `rows` (reserved for
// them). Blank lines are skipped; '#' lines are comments wherever they stand.
void ReadRows(std::string_view text, int line_number, const FlightTable& table, TableRows* rows) {
  internal::TextLine line;
  while (internal::NextLine(&text, &line_number, &line)) {
    const std::string_view trimmed = TrimSpaces(line.text);
    if (trimmed.empty()) continue;
    if (trimmed.front() == '#')
      ReadCommentLine(trimmed, &rows->metadata);
    else
      ReadRow(line, table, rows);
  }
}

// A log's rows are parsed in this many stretches at once, split at line ends; below
// kParallelParseBytes in one (a thread costs more than it saves there).
constexpr int kParseThreads = 2;
constexpr size_t kParallelParseBytes = size_t{1} << 20;

// The rows after the header, `body`, whose line before the first is `line_number`. The stretches'
// rows, comments and errors come out in file order, as if read in one pass.
void ReadBody(std::string_view body, int line_number, FlightTable* table) {
  std::vector<std::string_view> stretches;
  std::vector<int> first_lines;
  std::vector<TableRows> parts;
  while (!body.empty()) {
    const size_t remaining = static_cast<size_t>(kParseThreads) - stretches.size();
    size_t end = body.size();
    if (remaining > 1 && body.size() >= kParallelParseBytes) {
      const size_t newline = body.find('\n', body.size() / remaining);
      end = newline == std::string_view::npos ? body.size() : newline + 1;
    }
    stretches.push_back(body.substr(0, end));
    first_lines.push_back(line_number);
    const size_t lines = static_cast<size_t>(std::count(stretches.back().begin(), stretches.back().end(), '\n'));
    line_number += static_cast<int>(lines);
    // Allocated here, not by the parsing threads: memory a thread allocates stays in its own
    // arena once freed (glibc), where this thread's later arrays cannot reuse it (1 h log: +60 MB).
    parts.push_back(ReserveRows(*table, lines + 1));
    body.remove_prefix(end);
  }
  std::vector<std::exception_ptr> failures(stretches.size());
  internal::ParallelFor(static_cast<int>(stretches.size()), kParseThreads, [&](int i) {
    try {
      ReadRows(stretches[i], first_lines[i], *table, &parts[i]);
    } catch (...) {
      failures[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
  for (TableRows& part : parts)
    for (auto& [key, value] : part.metadata) table->metadata[key] = std::move(value);
  table->parts = std::move(parts);
}

// Comments and blank lines may precede the header; the first other line is the header.
FlightTable ReadTable(const std::string& text, const std::string& source) {
  FlightTable table;
  table.source = source;
  std::string_view rest(text);
  // A UTF-8 byte-order mark (spreadsheet exports) would become part of the first column's name.
  if (rest.substr(0, 3) == "\xEF\xBB\xBF") rest.remove_prefix(3);
  int line_number = 0;
  internal::TextLine line;
  while (!table.has_header && internal::NextLine(&rest, &line_number, &line)) {
    const std::string_view trimmed = TrimSpaces(line.text);
    if (trimmed.empty()) continue;
    if (trimmed.front() == '#')
      ReadCommentLine(trimmed, &table.metadata);
    else
      ReadHeader(line, &table);
  }
  if (!table.has_header) throw Error(source + ": empty file: no header line and no samples");
  ReadBody(rest, line_number, &table);
  return table;
}

Eigen::MatrixX3d ReadVector3(const FlightTable& table, const std::string& prefix) {
  Eigen::MatrixX3d out(table.num_rows(), 3);
  const char* axes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) out.col(a) = table.Column(table.Require(prefix + axes[a]));
  return out;
}

// rotor_1..rotor_N; N from the header when `num_rotors` < 0.
Eigen::MatrixXd ReadRotors(const FlightTable& table, int num_rotors) {
  const std::string& source = table.source;
  if (num_rotors < 0) {
    num_rotors = 0;
    while (table.Find("rotor_" + std::to_string(num_rotors + 1))) ++num_rotors;
    if (num_rotors == 0) throw Error(Located(source, table.header_line, 0, "missing required column 'rotor_1'"));
  }
  // A rotor the vehicle file leaves out would be dropped silently.
  if (const auto extra = table.Find("rotor_" + std::to_string(num_rotors + 1)))
    throw Error(Located(source, table.header_line, CellColumn(table.header_text, *extra),
                        "the log has column 'rotor_" + std::to_string(num_rotors + 1) + "' but the vehicle file has " +
                            std::to_string(num_rotors) + " rotors: give every rotor in the vehicle file"));
  std::vector<int> rotor_columns;  // all located before any allocation that scales with the count
  for (int r = 0; r < num_rotors; ++r) rotor_columns.push_back(table.Require("rotor_" + std::to_string(r + 1)));
  Eigen::MatrixXd rotors(table.num_rows(), num_rotors);
  for (int r = 0; r < num_rotors; ++r) {
    rotors.col(r) = table.Column(rotor_columns[r]);
    if ((rotors.col(r).array() < 0.0).any())
      throw Error(Located(
          source, table.header_line, 0,
          "column 'rotor_" + std::to_string(r + 1) + "' has negative rotor speeds; it must hold |Omega| in rad/s"));
  }
  return rotors;
}

// roll, pitch, yaw, else the quaternion qw, qx, qy, qz turned into them.
Eigen::MatrixX3d ReadAttitude(const FlightTable& table) {
  const int n = static_cast<int>(table.num_rows());
  Eigen::MatrixX3d bryant(n, 3);
  if (table.Find("roll")) {
    bryant.col(0) = table.Column(table.Require("roll"));
    bryant.col(1) = table.Column(table.Require("pitch"));
    bryant.col(2) = table.Column(table.Require("yaw"));
  } else if (table.Find("qw")) {
    const auto qw = table.Column(table.Require("qw")), qx = table.Column(table.Require("qx")),
               qy = table.Column(table.Require("qy")), qz = table.Column(table.Require("qz"));
    for (int i = 0; i < n; ++i) {
      Eigen::Quaterniond q(qw[i], qx[i], qy[i], qz[i]);
      if (!(q.norm() > 0.5))
        throw Error(table.source + ": quaternion of data row " + std::to_string(i + 1) + " is not a rotation");
      bryant.row(i) = RotationToBryant(q.normalized().toRotationMatrix()).transpose();
    }
  } else {
    throw Error(Located(table.source, table.header_line, 0, "pos_x..z given without roll,pitch,yaw or qw,qx,qy,qz"));
  }
  return bryant;
}

// Position with attitude, and the velocity when given; the velocity alone is refused.
std::optional<MocapTrack> ReadMocap(const FlightTable& table) {
  if (!table.Find("pos_x")) {
    if (const auto k = table.Find("vel_x")) {
      throw Error(Located(table.source, table.header_line, CellColumn(table.header_text, *k),
                          "vel_x..z (world frame) need the pose (pos_x..z with roll,pitch,yaw or qw,qx,qy,qz) to be "
                          "turned into the body frame"));
    }
    return std::nullopt;
  }
  MocapTrack mocap;
  mocap.position_w_m = ReadVector3(table, "pos_");
  mocap.bryant_rad = ReadAttitude(table);
  if (table.Find("vel_x")) mocap.velocity_w_mps = ReadVector3(table, "vel_");
  return mocap;
}

// Metadata 'gravity', else standard gravity.
double ReadGravity(const std::map<std::string, std::string>& metadata, const std::string& source) {
  const auto it = metadata.find("gravity");
  if (it == metadata.end()) return kStandardGravity;
  double g = 0.0;
  // Unlike a data cell, the number may be followed by text ("9.81 m/s^2").
  const auto result = fast_float::from_chars(it->second.data(), it->second.data() + it->second.size(), g);
  if (result.ec != std::errc() || !(g > 0.0) || !std::isfinite(g))
    throw Error(source + ": metadata 'gravity' must be a positive number, got '" + it->second + "'");
  return g;
}

}  // namespace

FlightLog ParseFlightCsv(const std::string& text, const std::string& source, int num_rotors) {
  FlightTable table = ReadTable(text, source);
  table.Require("t");
  for (const char* name : {"gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"}) table.Require(name);
  internal::RequireMinFlightSamples(source, static_cast<int>(table.num_rows()));

  FlightLog log;
  log.source = source;
  log.t_s = internal::TimesFromStamps(table.TimeStamps(), &table.metadata);
  if (const std::optional<int> i = internal::FirstNonIncreasingTime(log.t_s)) {
    throw Error(Located(source, table.RowLine(*i), 1,
                        "time goes backwards or repeats: t = " + std::to_string(log.t_s[*i]) + " after " +
                            std::to_string(log.t_s[*i - 1])));
  }
  log.gyro_radps = ReadVector3(table, "gyro_");
  log.acc_mps2 = ReadVector3(table, "acc_");
  log.rotor_radps = ReadRotors(table, num_rotors);
  log.mocap = ReadMocap(table);
  if (const auto k = table.Find("voltage")) log.voltage_v = table.Column(*k);
  log.gravity_mps2 = ReadGravity(table.metadata, source);
  log.metadata = std::move(table.metadata);
  return log;
}

FlightLog ReadFlightCsv(const std::string& path, int num_rotors) {
  return ParseFlightCsv(ReadFile(path), path, num_rotors);
}

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
