#include "rotorid/io/crazyflie_usd.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

// Builds uSD logs byte by byte, as the firmware writes them.
class UsdBuilder {
 public:
  explicit UsdBuilder(int version = 2) {
    bytes_.push_back('\xBC');
    U16(static_cast<uint16_t>(version));
    version_ = version;
  }
  UsdBuilder& U8(uint8_t v) {
    bytes_.push_back(static_cast<char>(v));
    return *this;
  }
  UsdBuilder& U16(uint16_t v) { return Raw(&v, 2); }
  UsdBuilder& U32(uint32_t v) { return Raw(&v, 4); }
  UsdBuilder& U64(uint64_t v) { return Raw(&v, 8); }
  UsdBuilder& F32(float v) { return Raw(&v, 4); }
  UsdBuilder& Str(const std::string& s) {
    bytes_ += s;
    bytes_.push_back('\0');
    return *this;
  }
  UsdBuilder& Raw(const void* p, size_t n) {
    bytes_.append(static_cast<const char*>(p), n);
    return *this;
  }
  UsdBuilder& Event(uint16_t id, const std::string& name, const std::vector<std::string>& variables) {
    U16(id).Str(name).U16(static_cast<uint16_t>(variables.size()));
    for (const auto& v : variables) Str(v);
    return *this;
  }
  UsdBuilder& Record(uint16_t id, uint64_t t) {
    U16(id);
    return version_ == 1 ? U32(static_cast<uint32_t>(t)) : U64(t);
  }
  // The finished file: everything so far plus its CRC32.
  std::string Finish() const {
    std::string out = bytes_;
    const uint32_t crc = Crc32(out.data(), out.size());
    out.append(reinterpret_cast<const char*>(&crc), 4);
    return out;
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
  int version_ = 2;
};

std::string TwoEventLog(int version) {
  UsdBuilder b(version);
  b.U16(2);
  b.Event(0xFFFF, "fixedFrequency", {"gyro.x(f)", "rpm.m1(H)", "pwm.m4_pwm(I)", "acc.z(f)"});
  b.Event(8, "estPose", {"locSrv.x(f)", "locSrv.qw(f)"});
  for (int i = 0; i < 5; ++i) {
    b.Record(0xFFFF, 1000 + 2 * i).F32(0.5f * i).U16(static_cast<uint16_t>(19000 + i)).U32(65535u - i).F32(1.0f);
    if (i % 2 == 0) b.Record(8, 1001 + 2 * i).F32(-0.25f * i).F32(1.0f);
  }
  return b.Finish();
}

TEST(CrazyflieUsd, Crc32MatchesZlib) {
  EXPECT_EQ(Crc32("123456789", 9), 0xCBF43926u);  // the standard check value
  EXPECT_EQ(Crc32("", 0), 0u);
  // Slice-by-8 and the byte loop agree on every length and split.
  std::string data;
  for (int i = 0; i < 100; ++i) data.push_back(static_cast<char>(i * 37 + 11));
  for (size_t n = 0; n <= data.size(); ++n) {
    const uint32_t whole = Crc32(data.data(), n);
    EXPECT_EQ(Crc32(data.data() + n / 3, n - n / 3, Crc32(data.data(), n / 3)), whole) << n;
  }
}

TEST(CrazyflieUsd, DecodesVersion2EventsIntoTables) {
  const CrazyflieUsdLog log = ParseCrazyflieUsd(TwoEventLog(2), "mem");
  EXPECT_EQ(log.version, 2);
  ASSERT_EQ(log.events.size(), 2u);
  const UsdEventTable* ff = log.FindEvent("fixedFrequency");
  ASSERT_NE(ff, nullptr);
  EXPECT_EQ(ff->id, 0xFFFF);
  ASSERT_EQ(ff->num_records(), 5);
  EXPECT_EQ(ff->payload_bytes, 4 + 2 + 4 + 4);
  EXPECT_EQ(ff->variables[1].name, "rpm.m1");
  EXPECT_EQ(ff->variables[1].type_char, 'H');
  EXPECT_EQ(ff->timestamp_us[4], 1008u);
  EXPECT_EQ((*ff->FindColumn("gyro.x"))[3], 1.5);
  EXPECT_EQ((*ff->FindColumn("rpm.m1"))[2], 19002.0);
  EXPECT_EQ((*ff->FindColumn("pwm.m4_pwm"))[1], 65534.0);
  EXPECT_EQ(ff->FindColumn("gyro.y"), nullptr);
  const UsdEventTable* pose = log.FindEvent("estPose");
  ASSERT_NE(pose, nullptr);
  ASSERT_EQ(pose->num_records(), 3);
  EXPECT_EQ(pose->timestamp_us[2], 1009u);
  EXPECT_EQ((*pose->FindColumn("locSrv.x"))[2], -1.0);
  EXPECT_EQ(log.DescribeEvents(), "fixedFrequency (5 records), estPose (3 records)");
}

TEST(CrazyflieUsd, Version1TimestampsAreMillisecondTicks) {
  const CrazyflieUsdLog log = ParseCrazyflieUsd(TwoEventLog(1), "mem");
  EXPECT_EQ(log.version, 1);
  const UsdEventTable* ff = log.FindEvent("fixedFrequency");
  ASSERT_NE(ff, nullptr);
  ASSERT_EQ(ff->num_records(), 5);
  EXPECT_EQ(ff->timestamp_us[0], 1000u * 1000u);
  EXPECT_EQ(ff->timestamp_us[4], 1008u * 1000u);
  EXPECT_EQ((*ff->FindColumn("rpm.m1"))[4], 19004.0);
}

TEST(CrazyflieUsd, DecodesEveryTypeCharacter) {
  UsdBuilder b;
  b.U16(1).Event(3, "all",
                 {"a.u8(B)", "a.i8(b)", "a.u16(H)", "a.i16(h)", "a.u32(I)", "a.i32(i)", "a.f(f)", "a.half(e)"});
  b.Record(3, 7).U8(250).U8(0xFB).U16(65000).U16(0x8000).U32(4000000000u).U32(0x80000000u).F32(-1.25f).U16(0x3E00);
  b.Record(3, 8).U8(0).U8(0x7F).U16(0).U16(0x7FFF).U32(0).U32(0x7FFFFFFFu).F32(3.0e38f).U16(0x0001);
  b.Record(3, 9).U8(1).U8(0).U16(1).U16(0xFFFF).U32(1).U32(0xFFFFFFFFu).F32(0.0f).U16(0xFBFF);
  const CrazyflieUsdLog log = ParseCrazyflieUsd(b.Finish(), "mem");
  const UsdEventTable& e = log.events.at(0);
  ASSERT_EQ(e.num_records(), 3);
  auto col = [&](const char* name) { return *e.FindColumn(name); };
  EXPECT_EQ(col("a.u8")[0], 250.0);
  EXPECT_EQ(col("a.i8")[0], -5.0);
  EXPECT_EQ(col("a.i8")[1], 127.0);
  EXPECT_EQ(col("a.u16")[0], 65000.0);
  EXPECT_EQ(col("a.i16")[0], -32768.0);
  EXPECT_EQ(col("a.i16")[2], -1.0);
  EXPECT_EQ(col("a.u32")[0], 4000000000.0);
  EXPECT_EQ(col("a.i32")[0], -2147483648.0);
  EXPECT_EQ(col("a.i32")[1], 2147483647.0);
  EXPECT_EQ(col("a.f")[0], -1.25);
  EXPECT_EQ(col("a.f")[1], static_cast<double>(3.0e38f));
  EXPECT_EQ(col("a.half")[0], 1.5);
  EXPECT_EQ(col("a.half")[1], std::ldexp(1.0, -24));  // smallest subnormal
  EXPECT_EQ(col("a.half")[2], -65504.0);              // largest finite, negative
}

TEST(CrazyflieUsd, EventsWithoutRecordsAndEmptyLogsAreKept) {
  UsdBuilder b;
  b.U16(1).Event(0xFFFF, "fixedFrequency", {"gyro.x(f)"});
  const CrazyflieUsdLog log = ParseCrazyflieUsd(b.Finish(), "mem");
  ASSERT_EQ(log.events.size(), 1u);
  EXPECT_EQ(log.events[0].num_records(), 0);
  EXPECT_EQ(log.events[0].columns.size(), 1u);
}

// Error messages carry the file name, the byte offset and what is wrong.
void ExpectError(const std::string& bytes, const std::string& fragment, const CrazyflieUsdOptions& options = {}) {
  try {
    ParseCrazyflieUsd(bytes, "flight.bin", options);
    ADD_FAILURE() << "no error; expected '" << fragment << "'";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("flight.bin: byte ", 0), 0u) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
  }
}

TEST(CrazyflieUsd, CorruptFilesGiveNamedErrors) {
  const std::string good = TwoEventLog(2);
  ExpectError("", "file too short (0 bytes)");
  ExpectError(std::string("\xBC\x02\x00", 3), "file too short");
  std::string bad_magic = good;
  bad_magic[0] = 'X';
  ExpectError(bad_magic, "byte 0: not a Crazyflie uSD log: first byte is 0x58");
  std::string bad_version = good;
  bad_version[1] = 3;
  ExpectError(bad_version, "byte 1: unsupported uSD log version 3");
  std::string flipped = good;
  flipped[200] ^= 0x10;
  ExpectError(flipped, "CRC32 mismatch");
  ExpectError(good.substr(0, good.size() - 7), "CRC32 mismatch");

  // Structural errors, with a valid CRC so that the structure is what fails.
  UsdBuilder unknown;
  unknown.U16(1).Event(1, "a", {"x.y(f)"}).Record(1, 5).F32(1.f).Record(9, 6).F32(2.f);
  ExpectError(unknown.Finish(), "record with event id 9, which the header does not define (defined: 1 a)");
  UsdBuilder cut;
  cut.U16(1).Event(1, "a", {"x.y(f)", "x.z(f)"}).Record(1, 5).F32(1.f).F32(2.f).Record(1, 6).F32(2.f);
  const std::string cut_bytes = cut.Finish();
  ExpectError(cut_bytes, "record of event 'a' needs 18 bytes, only 14 are left before the CRC");
  ExpectError(cut_bytes, "byte " + std::to_string(cut_bytes.size() - 4 - 14) + ":");
  UsdBuilder short_header;
  short_header.U16(1).Event(1, "a", {}).Record(1, 5).U8(0);
  ExpectError(short_header.Finish(), "record header needs 10 bytes, only 1 are left");
  UsdBuilder bad_type;
  bad_type.U16(1).Event(1, "a", {"x.y(q)"});
  ExpectError(bad_type.Finish(), "unknown type character 'q'");
  UsdBuilder bad_variable;
  bad_variable.U16(1).Event(1, "a", {"gyro.x"});
  ExpectError(bad_variable.Finish(), "is 'gyro.x', expected 'name(T)'");
  UsdBuilder twice_id;
  twice_id.U16(2).Event(1, "a", {}).Event(1, "b", {});
  ExpectError(twice_id.Finish(), "byte 11: event id 1 is defined twice ('a' and 'b')");
  UsdBuilder twice_name;
  twice_name.U16(2).Event(1, "a", {}).Event(2, "a", {});
  ExpectError(twice_name.Finish(), "event name 'a' is defined twice");
  UsdBuilder twice_variable;
  twice_variable.U16(1).Event(1, "a", {"x.y(f)", "x.y(H)"});
  ExpectError(twice_variable.Finish(), "'x.y' is listed twice");
  UsdBuilder many_events;
  many_events.U16(40000).Event(1, "a", {});
  ExpectError(many_events.Finish(), "header ends inside the id of event type 2 of 40000");
  UsdBuilder no_nul;
  no_nul.U16(1).U16(1).Raw("abc", 3);
  ExpectError(no_nul.Finish(), "the name of event type 1 of 1 has no terminating NUL");
  UsdBuilder empty_name;
  empty_name.U16(1).Event(1, "", {});
  ExpectError(empty_name.Finish(), "empty name for event type 1 of 1");
}

TEST(CrazyflieUsd, CrcCheckCanBeTurnedOff) {
  std::string bytes = TwoEventLog(2);
  bytes[bytes.size() - 1] ^= 0xFF;
  CrazyflieUsdOptions options;
  options.verify_crc = false;
  const CrazyflieUsdLog log = ParseCrazyflieUsd(bytes, "mem", options);
  EXPECT_EQ(log.FindEvent("fixedFrequency")->num_records(), 5);
  ExpectError(bytes, "CRC32 mismatch");
}

TEST(CrazyflieUsd, EveryTruncationAndByteFlipFailsCleanly) {
  const std::string good = TwoEventLog(2);
  CrazyflieUsdOptions no_crc;
  no_crc.verify_crc = false;
  for (size_t n = 0; n < good.size(); ++n) {
    EXPECT_THROW(ParseCrazyflieUsd(good.substr(0, n), "cut", {}), Error) << n;
    // Without the CRC check a cut file may still frame; it must never crash.
    try {
      ParseCrazyflieUsd(good.substr(0, n), "cut", no_crc);
    } catch (const Error&) {
    }
  }
  for (size_t i = 0; i < good.size(); ++i) {
    std::string flipped = good;
    flipped[i] ^= 0x5A;
    EXPECT_THROW(ParseCrazyflieUsd(flipped, "flip", {}), Error) << i;
    try {
      ParseCrazyflieUsd(flipped, "flip", no_crc);
    } catch (const Error&) {
    }
  }
}

TEST(CrazyflieUsd, ReadsFromFileAndNamesMissingFiles) {
  const std::string dir = testing::MakeTempDir("cf-usd");
  const std::string path = dir + "/log00";
  WriteFileAtomically(path, TwoEventLog(2));
  EXPECT_EQ(ReadCrazyflieUsd(path).FindEvent("estPose")->num_records(), 3);
  try {
    ReadCrazyflieUsd(dir + "/absent");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/absent"), std::string::npos);
  }
  std::filesystem::remove_all(dir);
}

// ---- Agreement with the CSVs decoded beside the real logs ----

struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

CsvTable LoadCsv(const std::string& path) {
  const std::string text = ReadFile(path);
  CsvTable table;
  size_t start = 0;
  bool first = true;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> cells;
    size_t c = 0;
    while (true) {
      const size_t comma = line.find(',', c);
      cells.push_back(line.substr(c, comma == std::string::npos ? std::string::npos : comma - c));
      if (comma == std::string::npos) break;
      c = comma + 1;
    }
    if (first) {
      table.header = std::move(cells);
      first = false;
    } else {
      table.rows.push_back(std::move(cells));
    }
  }
  return table;
}

bool IsIntegerType(char type_char) { return type_char != 'f' && type_char != 'e'; }

struct Agreement {
  long files = 0, tables = 0, rows = 0, cells = 0, text_mismatches = 0;
  double max_rel_float_diff = 0.0;
};

// Compares one event table with its CSV: header names, row count, every cell.
void CompareWithCsv(const UsdEventTable& event, const std::string& csv_path, Agreement* agreement) {
  SCOPED_TRACE(csv_path);
  const CsvTable csv = LoadCsv(csv_path);
  ASSERT_EQ(csv.header.size(), event.variables.size() + 1);
  EXPECT_EQ(csv.header[0], "t_us");
  for (size_t k = 0; k < event.variables.size(); ++k) EXPECT_EQ(csv.header[k + 1], event.variables[k].name);
  ASSERT_EQ(csv.rows.size(), static_cast<size_t>(event.num_records()));
  ++agreement->tables;
  char buffer[64];
  int reported = 0;
  for (size_t r = 0; r < csv.rows.size(); ++r) {
    const auto& row = csv.rows[r];
    ASSERT_EQ(row.size(), csv.header.size()) << "row " << r;
    EXPECT_EQ(row[0], std::to_string(event.timestamp_us[r])) << "row " << r;
    for (size_t k = 0; k < event.variables.size(); ++k) {
      const double ours = event.columns[k][r];
      const std::string& cell = row[k + 1];
      ++agreement->cells;
      if (IsIntegerType(event.variables[k].type_char)) {
        // Integers exactly.
        std::snprintf(buffer, sizeof(buffer), "%.0f", ours);
        if (cell != buffer) {
          ++agreement->text_mismatches;
          if (++reported < 5)
            ADD_FAILURE() << "row " << r << " " << csv.header[k + 1] << ": " << cell << " vs " << buffer;
        }
      } else {
        // Floats to the 7 significant digits printed: the CSV text must be our value printed
        // with %.7g, and the values may differ by at most half a unit in the 7th digit.
        std::snprintf(buffer, sizeof(buffer), "%.7g", ours);
        const double theirs = std::stod(cell);
        const double rel = std::abs(ours - theirs) / std::max(std::abs(ours), 1e-300);
        if (ours != 0.0 || theirs != 0.0) agreement->max_rel_float_diff = std::max(agreement->max_rel_float_diff, rel);
        if (cell != buffer || rel > 5e-7) {
          ++agreement->text_mismatches;
          if (++reported < 5)
            ADD_FAILURE() << "row " << r << " " << csv.header[k + 1] << ": " << cell << " vs " << buffer;
        }
      }
    }
    ++agreement->rows;
  }
}

void CheckFolder(const std::string& relative, Agreement* agreement) {
  const auto folder = testing::SharedDataPath(relative);
  if (!folder) return;
  std::vector<std::string> raws;
  for (const auto& entry : std::filesystem::directory_iterator(*folder + "/raw")) raws.push_back(entry.path().string());
  std::sort(raws.begin(), raws.end());
  for (const std::string& raw : raws) {
    SCOPED_TRACE(raw);
    const auto t0 = std::chrono::steady_clock::now();
    const CrazyflieUsdLog log = ReadCrazyflieUsd(raw);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const std::string name = std::filesystem::path(raw).filename().string();
    std::cout << "  " << relative << "/raw/" << name << ": v" << log.version << ", " << log.DescribeEvents() << ", "
              << std::filesystem::file_size(raw) << " bytes read in " << ms << " ms\n";
    ++agreement->files;
    for (const UsdEventTable& event : log.events) {
      const std::string csv =
          *folder + "/csv/" + name + (event.name == "fixedFrequency" ? "" : "_" + event.name) + ".csv";
      ASSERT_TRUE(std::filesystem::exists(csv)) << csv;
      CompareWithCsv(event, csv, agreement);
    }
  }
}

TEST(CrazyflieUsdRealData, AgreesWithEveryDecodedCsv) {
  const std::vector<std::string> folders = {"real/crazyflie-imrc-rpm/brushed", "real/crazyflie-imrc-rpm/brushless",
                                            "real/crazyflie-arpl-sysid"};
  bool any = false;
  for (const auto& f : folders) any = any || testing::SharedDataPath(f).has_value();
  if (!any) GTEST_SKIP() << "shared real Crazyflie data not present";
  Agreement agreement;
  for (const auto& f : folders) CheckFolder(f, &agreement);
  std::cout << "  compared " << agreement.files << " files, " << agreement.tables << " event tables, " << agreement.rows
            << " rows, " << agreement.cells << " cells: " << agreement.text_mismatches
            << " mismatches; max relative float difference " << agreement.max_rel_float_diff << "\n";
  EXPECT_EQ(agreement.files, 10);
  EXPECT_EQ(agreement.tables, 17);
  EXPECT_EQ(agreement.text_mismatches, 0);
  EXPECT_LE(agreement.max_rel_float_diff, 5e-7);
}

TEST(CrazyflieUsdRealData, ParsesAMegabyteInMilliseconds) {
  const auto path = testing::SharedDataPath("real/crazyflie-imrc-rpm/brushed/raw/jana06");
  if (!path) GTEST_SKIP() << "shared real Crazyflie data not present";
  const std::string bytes = ReadFile(*path);
  double best_ms = 1e9;
  for (int i = 0; i < 10; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const CrazyflieUsdLog log = ParseCrazyflieUsd(bytes, *path);
    best_ms =
        std::min(best_ms, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    ASSERT_EQ(log.events.size(), 2u);
  }
  std::cout << "  parse of " << bytes.size() << " bytes from memory: best of 10 " << best_ms << " ms\n";
  EXPECT_LT(best_ms, 100.0);  // a loose bound (shared machines, sanitizer builds); typically a few ms
}

}  // namespace
}  // namespace rotorid
