#include "rotorid/io/blackbox.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rotorid/core/error.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

// A log header with one I/P field list: each field as name, signed, I predictor, I encoding,
// P predictor, P encoding.
struct FieldSpec {
  std::string name;
  int is_signed, i_predictor, i_encoding, p_predictor, p_encoding;
};

std::string Join(const std::vector<FieldSpec>& fields, const std::function<std::string(const FieldSpec&)>& get) {
  std::string out;
  for (size_t i = 0; i < fields.size(); ++i) out += (i ? "," : "") + get(fields[i]);
  return out;
}

std::string Header(const std::vector<FieldSpec>& fields, const std::string& extra = "") {
  const auto num = [](int v) { return std::to_string(v); };
  std::string h = "H Product:Blackbox flight data recorder by Nicholas Sherlock\nH Data version:2\n";
  h += "H Field I name:" + Join(fields, [](const FieldSpec& f) { return f.name; }) + "\n";
  h += "H Field I signed:" + Join(fields, [&](const FieldSpec& f) { return num(f.is_signed); }) + "\n";
  h += "H Field I predictor:" + Join(fields, [&](const FieldSpec& f) { return num(f.i_predictor); }) + "\n";
  h += "H Field I encoding:" + Join(fields, [&](const FieldSpec& f) { return num(f.i_encoding); }) + "\n";
  h += "H Field P predictor:" + Join(fields, [&](const FieldSpec& f) { return num(f.p_predictor); }) + "\n";
  h += "H Field P encoding:" + Join(fields, [&](const FieldSpec& f) { return num(f.p_encoding); }) + "\n";
  return h + "H I interval:32\nH P interval:1/1\n" + extra;
}

std::string Bytes(std::initializer_list<int> bytes) {
  std::string out;
  for (int b : bytes) out.push_back(static_cast<char>(b));
  return out;
}

// Unsigned and zig-zag signed variable-byte integers, written independently of the decoder.
std::string Uvb(uint32_t v) {
  std::string out;
  while (v >= 0x80) {
    out.push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
  return out;
}
std::string Svb(int32_t v) { return Uvb((static_cast<uint32_t>(v) << 1) ^ static_cast<uint32_t>(v >> 31)); }

const std::string kEnd = "E" + Bytes({255}) + "End of log" + Bytes({0});

std::vector<int64_t> Row(const BlackboxLog& log, int frame) {
  std::vector<int64_t> row;
  for (int f = 0; f < log.main.num_fields(); ++f) row.push_back(log.main.at(frame, f));
  return row;
}

// Byte layouts worked out by hand from the format description (docs/blackbox.md), one I-frame
// each, so that the decoder is checked against the layout and not against a second copy of itself.
TEST(BlackboxEncodings, EachEncodingDecodesHandWrittenBytes) {
  const std::vector<FieldSpec> fields = {
      {"u", 0, 0, 1, 0, 1},    {"s", 1, 0, 0, 0, 0},    {"n14a", 1, 0, 3, 0, 0}, {"n14b", 1, 0, 3, 0, 0},
      {"z", 1, 0, 9, 0, 9},    {"t0", 1, 0, 7, 0, 7},   {"t1", 1, 0, 7, 0, 7},   {"t2", 1, 0, 7, 0, 7},
      {"q0", 1, 0, 8, 0, 8},   {"q1", 1, 0, 8, 0, 8},   {"q2", 1, 0, 8, 0, 8},   {"q3", 1, 0, 8, 0, 8},
      {"g0", 1, 0, 6, 0, 6},   {"g1", 1, 0, 6, 0, 6},   {"g2", 1, 0, 6, 0, 6},   {"v0", 1, 0, 10, 0, 10},
      {"v1", 1, 0, 10, 0, 10}, {"v2", 1, 0, 10, 0, 10}, {"lone", 1, 0, 6, 0, 0},
  };
  // Each tag2_3s32 / tag2_3svariable case in its own frame: the selector byte picks the packing.
  const std::vector<std::pair<std::string, std::vector<int64_t>>> tag2 = {
      {Bytes({0x1C}), {1, -1, 0}},                                                // 2-bit fields
      {Bytes({0x45, 0xD7}), {5, -3, 7}},                                          // 4-bit
      {Bytes({0x94, 0x2C, 0x1F}), {20, -20, 31}},                                 // 6-bit
      {Bytes({0xE4, 0x64, 0x18, 0xFC, 0xA0, 0x86, 0x01}), {100, -1000, 100000}},  // 8/16/24-bit
  };
  const std::vector<std::pair<std::string, std::vector<int64_t>>> variable = {
      {Bytes({0x4F, 0x83}), {7, -8, 3}},             // 5-5-4 bits
      {Bytes({0xA7, 0x19, 0x40}), {-100, 50, -64}},  // 8-7-7 bits
      {Bytes({0x1C}), {1, -1, 0}},                   // 2-bit fields, as tag2_3s32
      {Bytes({0xE4, 0x64, 0x18, 0xFC, 0xA0, 0x86, 0x01}), {100, -1000, 100000}},
  };
  std::string data;
  for (size_t k = 0; k < tag2.size(); ++k) {
    data += "I" + Bytes({0xAC, 0x02}) + Bytes({0x05}) + Bytes({0x05}) + Bytes({0x9C, 0x7F});  // 300, -3, -5, 100
    data += tag2[k].first;
    data += Bytes({0xE4, 0x39, 0xC0, 0x3E, 0x80});  // tag8_4s16: 0, 4-bit 3, 8-bit -100, 16-bit 1000
    data += Bytes({0x06, 0x0A, 0x01});              // tag8_8svb group of 3: 0, 5, -1
    data += variable[k].first;
    data += Svb(-77);  // a tag8_8svb field alone: a bare signed VB
  }
  const std::vector<BlackboxLog> logs = DecodeBlackbox(Header(fields) + data + kEnd, "synthetic");
  ASSERT_EQ(logs.size(), 1u);
  const BlackboxLog& log = logs[0];
  EXPECT_TRUE(log.damage.empty()) << log.Summary();
  ASSERT_EQ(log.main.num_frames(), 4) << log.Summary();
  for (int k = 0; k < 4; ++k) {
    std::vector<int64_t> expected = {300, -3, -5, 100, 0};
    expected.insert(expected.end(), tag2[k].second.begin(), tag2[k].second.end());
    expected.insert(expected.end(), {0, 3, -100, 1000, 0, 5, -1});
    expected.insert(expected.end(), variable[k].second.begin(), variable[k].second.end());
    expected.push_back(-77);
    EXPECT_EQ(Row(log, k), expected) << "frame " << k;
  }
  EXPECT_TRUE(log.ended_cleanly);
}

TEST(BlackboxEncodings, Tag8_4S16DataVersion1PairsNibblesLowFirst) {
  const std::vector<FieldSpec> fields = {
      {"q0", 1, 0, 8, 0, 8}, {"q1", 1, 0, 8, 0, 8}, {"q2", 1, 0, 8, 0, 8}, {"q3", 1, 0, 8, 0, 8}};
  std::string header = Header(fields);
  header.replace(header.find("Data version:2"), 14, "Data version:1");
  // Selector 0b11_10_01_01: two 4-bit values in one byte (low nibble first), 8-bit, 16-bit LE.
  const std::string frame = "I" + Bytes({0xE5, 0xD3, 0x9C, 0xE8, 0x03});
  const BlackboxLog log = DecodeBlackbox(header + frame + kEnd, "v1").at(0);
  ASSERT_EQ(log.main.num_frames(), 1) << log.Summary();
  EXPECT_EQ(Row(log, 0), (std::vector<int64_t>{3, -3, -100, 1000}));
}

// Every predictor, through I- and P-frames: the test states each frame's values and writes the
// residuals the logger would, so a wrong prediction shows up as a wrong value.
TEST(BlackboxPredictors, EachPredictorReconstructsTheLoggedValues) {
  const std::vector<FieldSpec> fields = {
      {"loopIteration", 0, 0, 1, 6, 9},  // P: INCREMENT, no bytes
      {"time", 0, 0, 1, 2, 0},           // P: STRAIGHT_LINE
      {"gyroADC[0]", 1, 0, 0, 3, 0},     // P: AVERAGE_2
      {"rc", 1, 8, 0, 1, 0},             // I: 1500; P: PREVIOUS
      {"thr", 0, 4, 1, 1, 0},            // I: MINTHROTTLE
      {"vbat", 0, 9, 3, 1, 0},           // I: VBATREF with neg 14-bit
      {"motor[0]", 0, 11, 1, 3, 0},      // I: MINMOTOR
      {"motor[1]", 0, 5, 0, 3, 0},       // I: MOTOR_0
  };
  std::string header = Header(fields, "H minthrottle:1070\nH vbatref:1653\nH motorOutput:158,2047\n");
  header.replace(header.find("H P interval:1/1"), 16, "H P interval:4");  // Betaflight 4 style
  struct Frame {
    int64_t iteration, time, gyro, rc, thr, vbat, m0, m1;
  };
  const std::vector<Frame> frames = {{0, 1000, -40, 1400, 1100, 1600, 300, 310},
                                     {4, 3000, 11, 1420, 1120, 1590, 320, 330},
                                     {8, 5100, -7, 1430, 1100, 1580, 330, 300}};
  std::string data = "I" + Uvb(0) + Uvb(1000) + Svb(-40) + Svb(1400 - 1500) + Uvb(1100 - 1070) +
                     Uvb(static_cast<uint32_t>(-(1600 - 1653)) & 0x3fff) + Uvb(300 - 158) + Svb(310 - 300);
  for (size_t k = 1; k < frames.size(); ++k) {
    const Frame& f = frames[k];
    const Frame& p = frames[k - 1];
    const Frame& p2 = frames[k >= 2 ? k - 2 : k - 1];
    data += "P" + Svb(static_cast<int32_t>(f.time - (2 * p.time - p2.time))) +
            Svb(static_cast<int32_t>(f.gyro - (p.gyro + p2.gyro) / 2)) + Svb(static_cast<int32_t>(f.rc - p.rc)) +
            Svb(static_cast<int32_t>(f.thr - p.thr)) + Svb(static_cast<int32_t>(f.vbat - p.vbat)) +
            Svb(static_cast<int32_t>(f.m0 - (p.m0 + p2.m0) / 2)) + Svb(static_cast<int32_t>(f.m1 - (p.m1 + p2.m1) / 2));
  }
  const BlackboxLog log = DecodeBlackbox(header + data + kEnd, "predictors").at(0);
  ASSERT_EQ(log.main.num_frames(), 3) << log.Summary();
  EXPECT_EQ(log.i_frames, 1);
  EXPECT_EQ(log.p_frames, 2);
  for (int k = 0; k < 3; ++k) {
    const Frame& f = frames[k];
    EXPECT_EQ(Row(log, k), (std::vector<int64_t>{f.iteration, f.time, f.gyro, f.rc, f.thr, f.vbat, f.m0, f.m1}))
        << "frame " << k;
  }
}

TEST(BlackboxPredictors, GpsFramesUseHomeAndLastMainTime) {
  const std::vector<FieldSpec> fields = {{"loopIteration", 0, 0, 1, 6, 9}, {"time", 0, 0, 1, 2, 0}};
  const std::string gps_header =
      "H Field H name:GPS_home[0],GPS_home[1]\nH Field H signed:1,1\nH Field H predictor:0,0\n"
      "H Field H encoding:0,0\nH Field G name:time,GPS_coord[0],GPS_coord[1]\nH Field G signed:0,1,1\n"
      "H Field G predictor:10,7,7\nH Field G encoding:1,0,0\n";
  const std::string data = "I" + Uvb(0) + Uvb(5000) + "H" + Svb(520000000) + Svb(43000000) + "G" + Uvb(7) + Svb(-12) +
                           Svb(30) + "P" + Svb(0);
  const BlackboxLog log = DecodeBlackbox(Header(fields, gps_header) + data + kEnd, "gps").at(0);
  ASSERT_EQ(log.gps.num_frames(), 1) << log.Summary();
  EXPECT_EQ(log.gps.at(0, 0), 5007);
  EXPECT_EQ(log.gps.at(0, 1), 520000000 - 12);
  EXPECT_EQ(log.gps.at(0, 2), 43000030);
  EXPECT_EQ(log.gps.main_index[0], 1);
  EXPECT_EQ(log.main.num_frames(), 2);
}

// Two logs in one file, an unknown field kept by name, events and a slow frame.
TEST(BlackboxFile, SeveralLogsEventsAndUnknownFields) {
  const std::vector<FieldSpec> fields = {
      {"loopIteration", 0, 0, 1, 6, 9}, {"time", 0, 0, 1, 2, 0}, {"someForkField[3]", 1, 0, 0, 1, 0}};
  const std::string slow =
      "H Field S name:flightModeFlags\nH Field S signed:0\nH Field S predictor:0\nH Field S encoding:1\n";
  const std::string first = Header(fields, slow) + "S" + Uvb(5) + "I" + Uvb(0) + Uvb(100) + Svb(-9) + "P" + Svb(0) +
                            Svb(2) + "E" + Bytes({30}) + Uvb(1) + Uvb(0) + "E" + Bytes({15}) + Uvb(4) + kEnd;
  const std::string second = Header(fields) + "I" + Uvb(0) + Uvb(7) + Svb(1) + "E" + Bytes({14}) + Uvb(50) + Uvb(900) +
                             "I" + Uvb(50) + Uvb(900) + Svb(2);  // no log end: cut off
  const std::vector<BlackboxLog> logs = DecodeBlackbox(first + Bytes({0, 0, 0}) + second, "two");
  ASSERT_EQ(logs.size(), 2u);
  EXPECT_EQ(logs[0].main.num_frames(), 2);
  EXPECT_EQ(logs[0].main.at(1, logs[0].main.Find("someForkField[3]")), -7);
  EXPECT_EQ(logs[0].main.at(1, 1), 100);  // straight line from one frame: the previous value
  ASSERT_EQ(logs[0].slow.num_frames(), 1);
  EXPECT_EQ(logs[0].slow.at(0, 0), 5);
  ASSERT_EQ(logs[0].events.size(), 3u);
  EXPECT_EQ(logs[0].events[0].type, BlackboxEventType::kFlightMode);
  EXPECT_EQ(logs[0].events[1].type, BlackboxEventType::kDisarm);
  EXPECT_EQ(logs[0].events[1].data, std::vector<int64_t>{4});
  EXPECT_TRUE(logs[0].ended_cleanly);
  EXPECT_TRUE(logs[0].damage.empty());
  EXPECT_EQ(logs[1].index, 2);
  EXPECT_EQ(logs[1].main.num_frames(), 2);
  EXPECT_EQ(logs[1].main.at(1, 1), 900);
  EXPECT_FALSE(logs[1].ended_cleanly);
  EXPECT_EQ(logs[1].events.at(0).type, BlackboxEventType::kLoggingResume);
}

// A stream of I/P frames: 4 groups of one I-frame and three P-frames.
std::string FrameStream(std::vector<size_t>* frame_offsets) {
  std::string data;
  for (int group = 0; group < 4; ++group) {
    const uint32_t it0 = 4 * group;
    frame_offsets->push_back(data.size());
    data += "I" + Uvb(it0) + Uvb(1000 * it0) + Svb(group);
    for (int k = 1; k < 4; ++k) {
      frame_offsets->push_back(data.size());
      data += "P" + Svb(k == 1 ? 1000 : 0) + Svb(1);  // time on a straight line: 1000 us per frame
    }
  }
  return data;
}

const std::vector<FieldSpec> kStreamFields = {
    {"loopIteration", 0, 0, 1, 6, 9}, {"time", 0, 0, 1, 2, 0}, {"x", 1, 0, 0, 1, 0}};

TEST(BlackboxDamage, BadPFrameLosesOnlyItsGroup) {
  std::vector<size_t> offsets;
  std::string data = FrameStream(&offsets);
  data[offsets[5]] = '\x7f';  // group 1's first P-frame: no longer a frame marker
  const BlackboxLog log = DecodeBlackbox(Header(kStreamFields) + data + kEnd, "bad-p").at(0);
  // Lost: group 1's I-frame (no marker after it, so its end is in doubt), the bad frame, and the
  // two P-frames after it (their reference is gone) until group 2's I-frame.
  EXPECT_EQ(log.main.num_frames(), 12) << log.Summary();
  ASSERT_EQ(log.damage.size(), 1u) << log.Summary();
  EXPECT_EQ(log.p_frames_without_reference, 2);
  EXPECT_EQ(log.damage[0].offset, Header(kStreamFields).size() + offsets[4]);
  EXPECT_EQ(log.damage[0].what, "I-frame: no frame marker after it");
  // The frames kept have the right values (x counts up by one per P-frame).
  for (int k = 0; k < log.main.num_frames(); ++k) {
    const int64_t it = log.main.at(k, 0);
    EXPECT_EQ(log.main.at(k, 1), 1000 * it) << k;
    EXPECT_EQ(log.main.at(k, 2), it / 4 + it % 4) << k;
  }
  EXPECT_TRUE(log.ended_cleanly);
}

TEST(BlackboxDamage, GarbageInsideAFrameIsDetectedAndSkipped) {
  std::vector<size_t> offsets;
  std::string data = FrameStream(&offsets);
  // Group 2's I-frame gets a time that jumps back (same byte length): implausible, so it is
  // dropped, and its three P-frames with it.
  data.replace(offsets[8] + 2, 2, Uvb(200));
  const BlackboxLog log = DecodeBlackbox(Header(kStreamFields) + data + kEnd, "garbage").at(0);
  EXPECT_EQ(log.main.num_frames(), 12) << log.Summary();
  EXPECT_EQ(log.p_frames_without_reference, 3);
  ASSERT_EQ(log.damage.size(), 1u);
  EXPECT_EQ(log.damage[0].what, "I-frame: time 200 us after 7000 us");
}

TEST(BlackboxDamage, FileCutInsideAFrameKeepsEverythingBefore) {
  std::vector<size_t> offsets;
  const std::string data = FrameStream(&offsets);
  const std::string cut = Header(kStreamFields) + data.substr(0, offsets[13] + 2);  // inside group 3's 2nd P-frame
  // The I-frame's time is two bytes: cut after the marker and one byte of it.
  const std::string cut_i = Header(kStreamFields) + data.substr(0, offsets[12] + 3);
  const BlackboxLog log = DecodeBlackbox(cut, "cut").at(0);
  EXPECT_EQ(log.main.num_frames(), 13) << log.Summary();
  EXPECT_FALSE(log.ended_cleanly);
  const BlackboxLog log_i = DecodeBlackbox(cut_i, "cut-i").at(0);
  EXPECT_EQ(log_i.main.num_frames(), 12) << log_i.Summary();
  ASSERT_EQ(log_i.damage.size(), 1u);
  EXPECT_EQ(log_i.damage[0].what, "file ends inside an I-frame");
}

TEST(BlackboxDamage, NamedErrorsForNoLogAndABadHeader) {
  try {
    DecodeBlackbox("not a log at all", "x.bbl");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x.bbl: not a blackbox log"), std::string::npos) << e.what();
  }
  std::string header = Header(kStreamFields);
  header.replace(header.find("H Field I encoding:1,1,0"), 24, "H Field I encoding:1,1,5");
  const BlackboxLog log = DecodeBlackbox(header + "I", "bad").at(0);
  EXPECT_EQ(log.header_error, "I-frame field 'x': unknown encoding 5");
  EXPECT_EQ(log.main.num_frames(), 0);
}

// The staged real logs: frame counts, time spans and the absence of damage as in their SOURCE.md.
struct RealLog {
  const char* path;
  int frames;
  int64_t first_time_us, last_time_us;
};

TEST(BlackboxRealLogs, EveryFrameOfTheStagedLogsDecodes) {
  const std::vector<RealLog> real = {
      {"real/indiflight-tudelft-throw/raw/LOG00230.BFL", 13198, 263592811, 289768412},
      {"real/indiflight-tudelft-throw/raw/LOG00271.BFL", 4192, 433240646, 441554365},
      {"real/indiflight-tudelft-throw/raw/LOG00281.BFL", 21583, 630905587, 673700181},
      {"real/betaflight-fcblackbox-gecko/raw/btfl_002.bbl", 66640, -1, -1},
  };
  int found = 0;
  for (const RealLog& r : real) {
    const auto path = testing::SharedDataPath(r.path);
    if (!path) continue;
    ++found;
    const std::vector<BlackboxLog> logs = ReadBlackboxFile(*path);
    ASSERT_EQ(logs.size(), 1u) << r.path;
    const BlackboxLog& log = logs[0];
    EXPECT_EQ(log.main.num_frames(), r.frames) << r.path << ": " << log.Summary();
    EXPECT_TRUE(log.damage.empty()) << r.path << ": " << log.Summary();
    EXPECT_EQ(log.p_frames_without_reference, 0) << r.path;
    EXPECT_TRUE(log.ended_cleanly) << r.path;
    const int t = log.main.Find("time");
    const int n = log.main.num_frames();
    if (r.first_time_us >= 0) {
      EXPECT_EQ(log.main.at(0, t), r.first_time_us) << r.path;
      EXPECT_EQ(log.main.at(n - 1, t), r.last_time_us) << r.path;
    }
    // No gap above 10 ms, and every iteration step is the P interval (the INCREMENT predictor).
    const int it = log.main.Find("loopIteration");
    const long p_interval = log.HeaderInt("P interval", 1);
    for (int k = 1; k < n; ++k) {
      ASSERT_LT(log.main.at(k, t) - log.main.at(k - 1, t), 10000) << r.path << " frame " << k;
      const int64_t step = log.main.at(k, it) - log.main.at(k - 1, it);
      const bool resumed = std::any_of(log.events.begin(), log.events.end(), [&](const BlackboxEvent& e) {
        return e.type == BlackboxEventType::kLoggingResume && e.main_index == k;
      });
      if (step != p_interval && !resumed) {
        ADD_FAILURE() << r.path << ": iteration step " << step << " at frame " << k;
        break;
      }
    }
  }
  if (found == 0) GTEST_SKIP() << "real blackbox logs absent";
}

TEST(BlackboxRealLogs, GeckoDurationAndFields) {
  const auto path = testing::SharedDataPath("real/betaflight-fcblackbox-gecko/raw/btfl_002.bbl");
  if (!path) GTEST_SKIP() << "Gecko log absent";
  const BlackboxLog log = ReadBlackboxFile(*path).at(0);
  const int t = log.main.Find("time");
  const int n = log.main.num_frames();
  EXPECT_NEAR((log.main.at(n - 1, t) - log.main.at(0, t)) * 1e-6, 133.8, 0.05);
  EXPECT_EQ(log.Header("Firmware revision").rfind("Betaflight 4.2.8", 0), 0u);
  const int vbat = log.main.Find("vbatLatest");
  ASSERT_GE(vbat, 0);
  EXPECT_NEAR(log.main.at(0, vbat) * 0.01, 16.5, 0.2);  // 4S, full (SOURCE.md: 16.6 V sagging to 13.2 V)
}

}  // namespace
}  // namespace rotorid
