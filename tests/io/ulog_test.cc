#include "rotorid/io/ulog.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "rotorid/core/error.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

// ---------------------------------------------------------------------------------------------
// Helpers

using testing::Slurp;

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::string line;
  std::istringstream in(text);
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

std::string HoursMinutesSeconds(uint64_t seconds) {
  char text[64];
  std::snprintf(text, sizeof(text), "%llu:%02llu:%02llu", static_cast<unsigned long long>(seconds / 3600),
                static_cast<unsigned long long>(seconds / 60 % 60), static_cast<unsigned long long>(seconds % 60));
  return text;
}

// Python's repr() of a str (the listing prints info-multiple values as lists of lists of str).
std::string PythonStrRepr(const std::string& s) {
  const bool use_double = s.find('\'') != std::string::npos && s.find('"') == std::string::npos;
  const char quote = use_double ? '"' : '\'';
  std::string out(1, quote);
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\\' || ch == quote) {
      out += '\\';
      out += ch;
    } else if (ch == '\n') {
      out += "\\n";
    } else if (ch == '\r') {
      out += "\\r";
    } else if (ch == '\t') {
      out += "\\t";
    } else if (c < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "\\x%02x", c);
      out += hex;
    } else {
      out += ch;
    }
  }
  return out + quote;
}

const std::vector<std::string> kSamples = {"sample", "sample_appended_multiple", "sample_log_small",
                                           "sample_logging_tagged_and_default_params", "sample_px4_events"};
// The samples with an ulog_info listing.
const std::vector<std::string> kInfoListed = {"sample", "sample_appended_multiple"};

std::optional<std::string> SamplePath(const std::string& name) {
  return testing::SharedDataPath("ulog-samples/" + name);
}

// A tiny ULog writer for synthetic files.
class ULogBuilder {
 public:
  explicit ULogBuilder(uint64_t start_us = 1000, uint8_t version = 1) {
    const uint8_t magic[7] = {0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35};
    bytes_.append(reinterpret_cast<const char*>(magic), 7);
    bytes_ += static_cast<char>(version);
    Append(start_us);
  }
  template <typename T>
  void Append(T value) {
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  size_t Message(char type, const std::string& body) {
    const size_t at = bytes_.size();
    Append(static_cast<uint16_t>(body.size()));
    bytes_ += type;
    bytes_ += body;
    return at;
  }
  static std::string Pod(const void* p, size_t n) { return std::string(static_cast<const char*>(p), n); }
  template <typename T>
  static std::string Pod(T value) {
    return Pod(&value, sizeof(T));
  }
  void FlagBits(uint8_t incompat0, std::vector<uint64_t> offsets) {
    std::string body(16, '\0');
    body[0] = 1;  // compat: default parameters
    body[8] = static_cast<char>(incompat0);
    offsets.resize(3, 0);
    for (uint64_t o : offsets) body += Pod(o);
    Message('B', body);
  }
  void Format(const std::string& text) { Message('F', text); }
  void Info(const std::string& key, const std::string& value) {
    Message('I', std::string(1, static_cast<char>(key.size())) + key + value);
  }
  void InfoMultiple(bool continued, const std::string& key, const std::string& value) {
    Message('M',
            std::string(1, static_cast<char>(continued)) + std::string(1, static_cast<char>(key.size())) + key + value);
  }
  void Parameter(const std::string& key, const std::string& value) {
    Message('P', std::string(1, static_cast<char>(key.size())) + key + value);
  }
  void DefaultParameter(uint8_t bits, const std::string& key, const std::string& value) {
    Message('Q', std::string(1, static_cast<char>(bits)) + std::string(1, static_cast<char>(key.size())) + key + value);
  }
  void Add(uint8_t multi_id, uint16_t msg_id, const std::string& name) {
    Message('A', std::string(1, static_cast<char>(multi_id)) + Pod(msg_id) + name);
  }
  size_t Data(uint16_t msg_id, const std::string& payload) { return Message('D', Pod(msg_id) + payload); }
  void Logging(char level, uint64_t t, const std::string& text) { Message('L', std::string(1, level) + Pod(t) + text); }
  void Tagged(char level, uint16_t tag, uint64_t t, const std::string& text) {
    Message('C', std::string(1, level) + Pod(tag) + Pod(t) + text);
  }
  const std::string& bytes() const { return bytes_; }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

ULog Parse(const std::string& bytes, const ULogReadOptions& options = {}) {
  return ParseULog(bytes.data(), bytes.size(), "mem.ulg", options);
}

// Expects a rotorid::Error whose message contains every fragment.
void ExpectError(const std::string& bytes, const std::vector<std::string>& fragments,
                 const ULogReadOptions& options = {}) {
  try {
    Parse(bytes, options);
    ADD_FAILURE() << "no error; expected one containing '" << fragments.front() << "'";
  } catch (const Error& e) {
    for (const std::string& fragment : fragments)
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what() << "\n  lacks: " << fragment;
  }
}

// ---------------------------------------------------------------------------------------------
// pyulog's listings (ulog_info, ulog_messages) for the sample logs

struct InfoListing {
  std::string start, duration;
  std::string dropouts_line;
  std::map<std::string, std::string> info;
  std::map<std::string, std::string> info_multiple;  // verbose form: key -> repr
  struct Topic {
    std::string name;
    int multi_id, size;
    size_t count, total;
  };
  std::vector<Topic> topics;
};

InfoListing ParseInfoListing(const std::string& text) {
  InfoListing listing;
  enum { kHead, kInfo, kMultiple, kTopics } section = kHead;
  for (const std::string& line : Lines(text)) {
    if (line.rfind("Logging start time: ", 0) == 0) {
      const size_t comma = line.find(", duration: ");
      listing.start = line.substr(20, comma - 20);
      listing.duration = line.substr(comma + 12);
    } else if (line.rfind("Dropouts:", 0) == 0 || line == "No Dropouts") {
      listing.dropouts_line = line;
    } else if (line == "Info Messages:") {
      section = kInfo;
    } else if (line.rfind("Info Multiple Messages:", 0) == 0) {
      section = kMultiple;
    } else if (line.rfind("Name (multi id", 0) == 0) {
      section = kTopics;
    } else if (line.empty()) {
      continue;
    } else if (section == kInfo || section == kMultiple) {
      const size_t colon = line.find(": ");
      (section == kInfo ? listing.info : listing.info_multiple)[line.substr(1, colon - 1)] = line.substr(colon + 2);
    } else if (section == kTopics) {
      InfoListing::Topic topic;
      char name[256];
      unsigned long long count = 0, total = 0;
      if (std::sscanf(line.c_str(), " %255s (%d, %d) %llu %llu", name, &topic.multi_id, &topic.size, &count, &total) ==
          5) {
        topic.name = name;
        topic.count = count;
        topic.total = total;
        listing.topics.push_back(topic);
      }
    }
  }
  return listing;
}

class ULogSampleTest : public ::testing::TestWithParam<std::string> {};
class ULogInfoListingTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ULogInfoListingTest, MatchesPyulogInfoListing) {
  const auto log_path = SamplePath(GetParam() + ".ulg");
  const auto listing_path = SamplePath(GetParam() + "_info.txt");
  if (!log_path || !listing_path) GTEST_SKIP() << "ulog-samples absent";
  const InfoListing expected = ParseInfoListing(Slurp(*listing_path));
  const ULog log = ReadULog(*log_path);

  EXPECT_EQ(HoursMinutesSeconds(log.start_timestamp_us / 1000000), expected.start);
  EXPECT_EQ(HoursMinutesSeconds((log.last_timestamp_us - log.start_timestamp_us) / 1000000), expected.duration);

  std::string dropouts = "No Dropouts";
  if (!log.dropouts.empty()) {
    int max_ms = 0;
    for (const ULogDropout& d : log.dropouts) max_ms = std::max<int>(max_ms, d.duration_ms);
    char text[200];
    std::snprintf(text, sizeof(text), "Dropouts: count: %zu, total duration: %.1f s, max: %d ms, mean: %d ms",
                  log.dropouts.size(), log.DropoutTotalMs() / 1000.0, max_ms,
                  static_cast<int>(log.DropoutTotalMs() / static_cast<int>(log.dropouts.size())));
    dropouts = text;
  }
  EXPECT_EQ(dropouts, expected.dropouts_line);

  // Info messages: every listed one, and every one we read (pyulog hides perf_* unless verbose).
  bool listing_has_perf = false;
  for (const auto& [key, value] : expected.info) {
    listing_has_perf = listing_has_perf || key.rfind("perf_", 0) == 0;
    ASSERT_TRUE(log.info.count(key)) << key;
    EXPECT_EQ(log.info.at(key).ToString(), value) << key;
  }
  for (const auto& [key, value] : log.info)
    if (listing_has_perf || key.rfind("perf_", 0) != 0) {
      EXPECT_TRUE(expected.info.count(key)) << "not listed: " << key;
    }
  EXPECT_GT(expected.info.size(), 3u);

  // Info multiple messages, in the verbose form: a Python list of lists of str.
  for (const auto& [key, repr] : expected.info_multiple) {
    ASSERT_TRUE(log.info_multiple.count(key)) << key;
    std::string mine = "[";
    for (size_t i = 0; i < log.info_multiple.at(key).size(); ++i) {
      mine += i ? ", [" : "[";
      const auto& parts = log.info_multiple.at(key)[i];
      for (size_t j = 0; j < parts.size(); ++j) mine += (j ? ", " : "") + PythonStrRepr(parts[j].ToString());
      mine += "]";
    }
    mine += "]";
    EXPECT_EQ(mine.size(), repr.size()) << key;
    EXPECT_TRUE(mine == repr) << key << " differs";
  }

  // Topics: pyulog lists the instances that have data.
  std::vector<const ULogTopic*> with_data;
  for (const ULogTopic& topic : log.topics)
    if (topic.num_messages() > 0) with_data.push_back(&topic);
  ASSERT_EQ(with_data.size(), expected.topics.size());
  for (size_t i = 0; i < with_data.size(); ++i) {
    const ULogTopic& mine = *with_data[i];
    const InfoListing::Topic& theirs = expected.topics[i];
    EXPECT_EQ(mine.name(), theirs.name);
    EXPECT_EQ(mine.multi_id(), theirs.multi_id) << theirs.name;
    EXPECT_EQ(mine.message_size(), theirs.size) << theirs.name;
    EXPECT_EQ(mine.num_messages(), theirs.count) << theirs.name;
    EXPECT_EQ(mine.num_messages() * static_cast<size_t>(mine.message_size()), theirs.total) << theirs.name;
  }
  RecordProperty("topics_compared", static_cast<int>(expected.topics.size()));
}

// ulog_messages: string messages ('L'), sorted by time together with PX4 events. Event texts need
// the libevents metadata (pyulog downloads it when the log lacks it), which rotorid does not decode;
// for those lines we check that the 'event' topic holds an event of that level at that second.
TEST_P(ULogSampleTest, MatchesPyulogMessagesListing) {
  const auto log_path = SamplePath(GetParam() + ".ulg");
  const auto listing_path = SamplePath(GetParam() + "_messages.txt");
  if (!log_path || !listing_path) GTEST_SKIP() << "ulog-samples absent";
  const std::vector<std::string> expected = Lines(Slurp(*listing_path));
  const ULog log = ReadULog(*log_path);
  const bool px4 = log.info.count("sys_name") && log.info.at("sys_name").ToString() == "PX4";

  auto line_of = [](uint64_t t_us, const std::string& level, const std::string& text) {
    return HoursMinutesSeconds(t_us / 1000000) + " " + level + ": " + text;
  };
  std::vector<std::string> strings;
  for (const ULogLoggedMessage& m : log.logged_messages) {
    if (m.tag) continue;                                            // pyulog's listing shows untagged messages only
    if (px4 && !m.text.empty() && m.text.back() == '\t') continue;  // duplicated by an event
    strings.push_back(line_of(m.timestamp_us, m.LevelName(), m.text));
  }
  // Events present in the log as (second, level) lines without text.
  std::multiset<std::string> events;
  if (const ULogTopic* event = log.FindTopic("event")) {
    const std::vector<double> levels = event->Column("log_levels");
    static const char* const kLevels[] = {"EMERGENCY", "ALERT",  "CRITICAL", "ERROR",
                                          "WARNING",   "NOTICE", "INFO",     "DEBUG"};
    for (size_t i = 0; i < event->num_messages(); ++i) {
      const int level = (static_cast<int>(levels[i]) >> 4) & 0xf;
      if (level < 8) events.insert(line_of(event->timestamps_us()[i], kLevels[level], ""));
    }
  }
  // The string messages must appear in order; every other line must be an event of the log.
  size_t next = 0;
  int event_lines = 0;
  for (const std::string& line : expected) {
    if (next < strings.size() && line == strings[next]) {
      ++next;
      continue;
    }
    const size_t colon = line.find(": ");
    ASSERT_NE(colon, std::string::npos) << line;
    const auto it = events.find(line.substr(0, colon + 2));
    ASSERT_TRUE(it != events.end()) << "neither a string message nor an event of the log: " << line;
    events.erase(it);
    ++event_lines;
  }
  EXPECT_EQ(next, strings.size()) << "string message not in the listing: "
                                  << (next < strings.size() ? strings[next] : "");
  RecordProperty("string_lines", static_cast<int>(strings.size()));
  RecordProperty("event_lines", event_lines);
}

TEST_P(ULogSampleTest, ParsesWithoutWarningsAndDecodesColumns) {
  const auto log_path = SamplePath(GetParam() + ".ulg");
  if (!log_path) GTEST_SKIP() << "ulog-samples absent";
  const ULog log = ReadULog(*log_path);
  EXPECT_EQ(log.truncated_tail_bytes, 0u);
  EXPECT_EQ(log.num_unknown_messages, 0);
  const ULogTopic& imu = log.Topic("sensor_combined");
  ASSERT_GT(imu.num_messages(), 100u);
  const std::vector<double> acc_z = imu.Column("accelerometer_m_s2[2]");
  double mean = 0.0;
  for (double a : acc_z) mean += a / static_cast<double>(acc_z.size());
  EXPECT_GT(std::abs(mean), 3.0);  // gravity is there, in FRD: about -9.8 when level
  EXPECT_LT(std::abs(mean), 15.0);
  for (size_t i = 1; i < imu.num_messages(); ++i) ASSERT_GE(imu.timestamps_us()[i], imu.timestamps_us()[i - 1]);
  EXPECT_FALSE(log.parameters.empty());
  EXPECT_THROW(imu.Column("no_such_field"), Error);
}

INSTANTIATE_TEST_SUITE_P(Samples, ULogSampleTest, ::testing::ValuesIn(kSamples));
INSTANTIATE_TEST_SUITE_P(Samples, ULogInfoListingTest, ::testing::ValuesIn(kInfoListed));

TEST(ULogSamples, DefaultParametersTaggedMessagesAndMultiInstances) {
  const auto path = SamplePath("sample_logging_tagged_and_default_params.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const ULog log = ReadULog(*path);
  EXPECT_EQ(log.compat_flags[0] & 1, 1);
  EXPECT_FALSE(log.default_parameters_system.empty());
  int tagged = 0;
  for (const ULogLoggedMessage& m : log.logged_messages)
    if (m.tag) {
      ++tagged;
      EXPECT_EQ(*m.tag, 1);
      EXPECT_EQ(m.text, "tagged message test");
    }
  EXPECT_EQ(tagged, 3);
  int with_data = 0;
  for (const ULogTopic* instance : log.TopicInstances("estimator_attitude")) with_data += instance->num_messages() > 0;
  EXPECT_EQ(with_data, 3);
  EXPECT_GT(log.num_sync_messages, 0);
}

TEST(ULogSamples, AppendedDataIsRead) {
  const auto path = SamplePath("sample_appended_multiple.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const ULog log = ReadULog(*path);
  EXPECT_EQ(log.appended_offsets.size(), 3u);
  ASSERT_TRUE(log.info_multiple.count("hardfault_plain"));
  EXPECT_EQ(log.info_multiple.at("hardfault_plain").size(), 3u);  // one per appended segment
}

TEST(ULogSamples, Parses4MbFast) {
  const auto path = SamplePath("sample.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const std::string bytes = Slurp(*path);
  double best_s = 1e9;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const ULog log = Parse(bytes);
    best_s = std::min(best_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    ASSERT_EQ(log.Topic("sensor_combined").num_messages(), 17070u);
  }
  RecordProperty("parse_ms", std::to_string(best_s * 1e3));
  std::printf("parse of %zu bytes: %.1f ms\n", bytes.size(), best_s * 1e3);
  EXPECT_LT(best_s, 2.0);  // loose: sanitizer and debug builds run here too (Release: ~10 ms)
}

// ---------------------------------------------------------------------------------------------
// Truncated and corrupt files (from a real log, cut and damaged in memory)

// Byte offsets of the messages of a log (message walk without interpretation).
std::vector<size_t> MessageOffsets(const std::string& bytes) {
  std::vector<size_t> offsets;
  size_t pos = 16;
  while (pos + 3 <= bytes.size()) {
    uint16_t size;
    std::memcpy(&size, bytes.data() + pos, 2);
    if (pos + 3 + size > bytes.size()) break;
    offsets.push_back(pos);
    pos += 3 + size;
  }
  return offsets;
}

TEST(ULogCorrupt, TruncatedLastMessageIsToleratedOrAnErrorNamingTheOffset) {
  const auto path = SamplePath("sample.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const std::string bytes = Slurp(*path);
  const std::vector<size_t> offsets = MessageOffsets(bytes);
  size_t cut_message = 0;  // a data message of more than 10 bytes, in the middle of the file
  for (size_t i = offsets.size() / 2; i < offsets.size() && !cut_message; ++i)
    if (bytes[offsets[i] + 2] == 'D' && offsets[i + 1] - offsets[i] > 20) cut_message = offsets[i];
  ASSERT_GT(cut_message, 0u);
  const std::string cut = bytes.substr(0, cut_message + 10);  // header and 7 bytes of the payload

  const ULog tolerant = Parse(cut);
  EXPECT_EQ(tolerant.truncated_tail_bytes, 10u);
  EXPECT_FALSE(tolerant.warnings.empty());
  EXPECT_LT(tolerant.Topic("sensor_combined").num_messages(), 17070u);

  ULogReadOptions strict;
  strict.allow_truncated_end = false;
  ExpectError(cut, {"mem.ulg", "byte " + std::to_string(cut_message), "truncated"}, strict);

  // Cut inside a message header (2 of 3 bytes).
  const std::string in_header = bytes.substr(0, cut_message + 2);
  EXPECT_EQ(Parse(in_header).truncated_tail_bytes, 2u);
  ExpectError(in_header, {"byte " + std::to_string(cut_message)}, strict);
}

TEST(ULogCorrupt, CutInTheDefinitionsIsAnError) {
  const auto path = SamplePath("sample.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const std::string bytes = Slurp(*path);
  const std::vector<size_t> offsets = MessageOffsets(bytes);
  ExpectError(bytes.substr(0, offsets[5] + 4), {"byte " + std::to_string(offsets[5]), "definitions"});
  ExpectError(bytes.substr(0, 10), {"byte 0", "shorter than the 16-byte ULog header"});
  std::string bad_magic = bytes;
  bad_magic[1] = 'X';
  ExpectError(bad_magic, {"byte 0", "not a ULog file"});
}

TEST(ULogCorrupt, DamagedMessagesAreErrorsNamingTheOffset) {
  const auto path = SamplePath("sample.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const std::string bytes = Slurp(*path);
  const std::vector<size_t> offsets = MessageOffsets(bytes);
  // First data message in the second half of the file.
  size_t data_at = 0;
  for (size_t i = offsets.size() / 2; i < offsets.size() && !data_at; ++i)
    if (bytes[offsets[i] + 2] == 'D') data_at = offsets[i];
  ASSERT_GT(data_at, 0u);

  std::string bad_type = bytes;
  bad_type[data_at + 2] = '\x01';
  ExpectError(bad_type, {"byte " + std::to_string(data_at), "unknown message type 0x01"});

  std::string bad_id = bytes;
  bad_id[data_at + 3] = '\xfe';
  bad_id[data_at + 4] = '\xfe';
  ExpectError(bad_id, {"byte " + std::to_string(data_at), "msg_id 65278"});

  std::string bad_size = bytes;  // one byte shorter: the walk loses sync on the next message
  uint16_t size;
  std::memcpy(&size, bytes.data() + data_at, 2);
  --size;
  std::memcpy(bad_size.data() + data_at, &size, 2);
  ExpectError(bad_size, {"byte " + std::to_string(data_at), "data message of"});

  // A format field without the space between type and name (sizes unchanged).
  for (size_t at : offsets) {
    if (bytes[at + 2] != 'F') continue;
    std::string bad_format = bytes;
    bad_format[bytes.find(' ', at + 3)] = '_';
    ExpectError(bad_format, {"byte " + std::to_string(at), "is not 'type name'"});
    break;
  }
}

TEST(ULogCorrupt, RandomDamageNeverCrashes) {
  const auto path = SamplePath("sample_log_small.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const std::string bytes = Slurp(*path);
  std::mt19937 rng(7);
  int errors = 0, parsed = 0;
  for (int trial = 0; trial < 60; ++trial) {
    std::string damaged = bytes.substr(0, std::uniform_int_distribution<size_t>(0, bytes.size())(rng));
    const int flips = std::uniform_int_distribution<int>(0, 8)(rng);
    for (int f = 0; f < flips && !damaged.empty(); ++f)
      damaged[std::uniform_int_distribution<size_t>(0, damaged.size() - 1)(rng)] =
          static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
    try {
      Parse(damaged);
      ++parsed;
    } catch (const Error& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find("mem.ulg: byte "), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(errors, 0);
  EXPECT_GT(parsed, 0);
}

// ---------------------------------------------------------------------------------------------
// Synthetic logs: every message kind

TEST(ULogSynthetic, NestedTypesArraysPaddingAndAllMessageKinds) {
  ULogBuilder b(5000);
  b.FlagBits(0, {});
  b.Format("vec:float x;float y;uint8_t[2] _padding0;");
  b.Format("motor:uint64_t timestamp;int32_t rpm;");
  b.Format("sample:uint64_t timestamp;vec[2] v;vec w;int16_t[3] k;char[4] tag;bool ok;motor m;uint8_t[3] _padding0;");
  b.Info("char[3] sys_name", "PX4");
  b.Info("int32_t time_ref_utc", ULogBuilder::Pod<int32_t>(-2));
  b.Info("float ratio", ULogBuilder::Pod<float>(0.5f));
  b.Info("uint8_t[2] raw", std::string("\x01\x02", 2));
  b.InfoMultiple(false, "char[3] boot", "abc");
  b.InfoMultiple(true, "char[3] boot", "def");
  b.InfoMultiple(false, "char[2] boot", "gh");
  b.Parameter("int32_t SYS_AUTOSTART", ULogBuilder::Pod<int32_t>(4001));
  b.Parameter("float CA_ROTOR0_KM", ULogBuilder::Pod<float>(0.05f));
  b.DefaultParameter(3, "float MPC_THR_HOVER", ULogBuilder::Pod<float>(0.4f));
  b.Add(1, 7, "sample");
  auto payload = [](uint64_t t, float x) {
    std::string p = ULogBuilder::Pod(t);
    for (int i = 0; i < 2; ++i) p += ULogBuilder::Pod(x + i) + ULogBuilder::Pod(-x) + std::string(2, '\0');
    p += ULogBuilder::Pod(10 * x) + ULogBuilder::Pod(0.0f) + std::string(2, '\0');
    for (int16_t k : {1, -2, 3}) p += ULogBuilder::Pod(k);
    p += "abcd";
    p += '\x01';
    p += ULogBuilder::Pod(t - 1) + ULogBuilder::Pod<int32_t>(-1200);
    return p;  // trailing padding left out, as the logger does
  };
  b.Data(7, payload(6000, 1.5f));
  b.Logging('6', 6100, "hello");
  b.Parameter("float CA_ROTOR0_KM", ULogBuilder::Pod<float>(-0.05f));
  b.Message('S', std::string("\x2f\x73\x13\x20\x25\x0c\xbb\x12", 8));
  b.Message('O', ULogBuilder::Pod<uint16_t>(25));
  b.Data(7, payload(7000, 2.5f) + std::string(3, '\0'));  // with the trailing padding: accepted
  b.Tagged('4', 9, 7100, "tagged");
  b.Message('X', "future message type");
  b.Message('R', ULogBuilder::Pod<uint16_t>(7));

  const ULog log = Parse(b.bytes());
  EXPECT_EQ(log.file_version, 1);
  EXPECT_EQ(log.start_timestamp_us, 5000u);
  EXPECT_EQ(log.last_timestamp_us, 7000u);
  EXPECT_EQ(log.info.at("sys_name").ToString(), "PX4");
  EXPECT_EQ(log.info.at("time_ref_utc").ToString(), "-2");
  EXPECT_EQ(log.info.at("ratio").ToString(), "0.5");
  EXPECT_EQ(log.info.at("raw").ToString(), "b'\\x01\\x02'");
  ASSERT_EQ(log.info_multiple.at("boot").size(), 2u);
  EXPECT_EQ(log.info_multiple.at("boot")[0].size(), 2u);
  EXPECT_EQ(log.info_multiple.at("boot")[0][1].ToString(), "def");
  EXPECT_EQ(log.parameters.at("SYS_AUTOSTART").int_value, 4001);
  EXPECT_FALSE(log.parameters.at("SYS_AUTOSTART").is_float);
  EXPECT_FLOAT_EQ(log.parameters.at("CA_ROTOR0_KM").float_value, 0.05f);
  ASSERT_EQ(log.parameter_changes.size(), 1u);
  EXPECT_EQ(log.parameter_changes[0].timestamp_us, 6000u);
  EXPECT_FLOAT_EQ(log.parameter_changes[0].value.float_value, -0.05f);
  EXPECT_EQ(log.default_parameters_system.count("MPC_THR_HOVER"), 1u);
  EXPECT_EQ(log.default_parameters_current_setup.count("MPC_THR_HOVER"), 1u);
  EXPECT_EQ(log.num_sync_messages, 1);
  ASSERT_EQ(log.dropouts.size(), 1u);
  EXPECT_EQ(log.dropouts[0].duration_ms, 25);
  EXPECT_EQ(log.dropouts[0].timestamp_us, 6000u);
  EXPECT_EQ(log.num_unknown_messages, 1);
  ASSERT_EQ(log.logged_messages.size(), 2u);
  EXPECT_EQ(log.logged_messages[0].LevelName(), "INFO");
  EXPECT_EQ(log.logged_messages[0].text, "hello");
  EXPECT_FALSE(log.logged_messages[0].tag.has_value());
  EXPECT_EQ(log.logged_messages[1].LevelName(), "WARNING");
  EXPECT_EQ(*log.logged_messages[1].tag, 9);

  const ULogTopic& topic = log.Topic("sample", 1);
  EXPECT_EQ(topic.num_messages(), 2u);
  // 8 + 2*(4+4+2) + (4+4+2) + 3*2 + 4 + 1 + (8+4) = 61 (the trailing 3-byte padding is left out).
  EXPECT_EQ(topic.message_size(), 61);
  EXPECT_EQ(topic.timestamps_us(), (std::vector<uint64_t>{6000, 7000}));
  EXPECT_EQ(topic.Column("v[1].x"), (std::vector<double>{2.5, 3.5}));
  EXPECT_EQ(topic.Column("v[0].y"), (std::vector<double>{-1.5, -2.5}));
  EXPECT_TRUE(topic.HasField("v[0]._padding0[1]"));  // inner padding stays, as in pyulog
  EXPECT_EQ(topic.Column("w.x"), (std::vector<double>{15.0, 25.0}));
  EXPECT_EQ(topic.Column("k[1]"), (std::vector<double>{-2.0, -2.0}));
  EXPECT_EQ(topic.Column("tag[3]"), (std::vector<double>{'d', 'd'}));
  EXPECT_EQ(topic.Column("ok"), (std::vector<double>{1.0, 1.0}));
  EXPECT_EQ(topic.Column("m.rpm"), (std::vector<double>{-1200.0, -1200.0}));
  EXPECT_EQ(topic.Column("m.timestamp"), (std::vector<double>{5999.0, 6999.0}));
  EXPECT_FALSE(topic.HasField("_padding0[0]"));
  EXPECT_EQ(log.FindTopic("sample", 0), nullptr);
  EXPECT_THROW(log.Topic("sample", 0), Error);
}

TEST(ULogSynthetic, AppendedSegmentsAndTopicFilter) {
  ULogBuilder b;
  b.FlagBits(1, {});  // offsets patched below
  b.Format("t:uint64_t timestamp;float a;");
  b.Format("u:uint64_t timestamp;");
  b.Add(0, 1, "t");
  b.Add(0, 2, "u");
  b.Data(1, ULogBuilder::Pod<uint64_t>(10) + ULogBuilder::Pod(1.0f));
  const size_t cut_at = b.Data(2, ULogBuilder::Pod<uint64_t>(11));
  b.bytes().resize(cut_at + 5);  // the logger crashed mid-message ...
  const uint64_t appended = b.bytes().size();
  b.Data(1, ULogBuilder::Pod<uint64_t>(20) + ULogBuilder::Pod(2.0f));  // ... and data was appended later
  std::memcpy(b.bytes().data() + 16 + 3 + 16, &appended, 8);

  const ULog log = Parse(b.bytes());
  EXPECT_EQ(log.appended_offsets, (std::vector<uint64_t>{appended}));
  EXPECT_EQ(log.num_cut_before_appended, 1);
  EXPECT_EQ(log.Topic("t").Column("a"), (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(log.Topic("u").num_messages(), 0u);

  ULogReadOptions only_u;
  only_u.topics = {"u"};
  const ULog filtered = Parse(b.bytes(), only_u);
  EXPECT_EQ(filtered.FindTopic("t"), nullptr);
  EXPECT_NE(filtered.FindTopic("u"), nullptr);

  std::string bad = b.bytes();
  const uint64_t beyond = bad.size() + 1;
  std::memcpy(bad.data() + 16 + 3 + 16, &beyond, 8);
  ExpectError(bad, {"byte 16", "appended data offset"});
}

TEST(ULogSynthetic, MalformedDefinitionsAreNamedErrors) {
  auto with = [](const std::function<void(ULogBuilder&)>& add) {
    ULogBuilder b;
    add(b);
    return b.bytes();
  };
  ExpectError(with([](ULogBuilder& b) {
                b.Format("a:uint64_t timestamp;b x;");
                b.Format("b:a y;");
                b.Add(0, 1, "a");
              }),
              {"byte 53", "nests deeper"});
  ExpectError(with([](ULogBuilder& b) { b.Add(0, 1, "nothing"); }),
              {"byte 16", "no format definition for type 'nothing'"});
  ExpectError(with([](ULogBuilder& b) {
                b.Format("a:float x;");
                b.Add(0, 1, "a");
              }),
              {"no 'timestamp' field"});
  ExpectError(with([](ULogBuilder& b) { b.Format("a:float[x] y;"); }), {"byte 16", "bad array size"});
  ExpectError(with([](ULogBuilder& b) { b.Format("a:floaty;"); }), {"is not 'type name'"});
  ExpectError(with([](ULogBuilder& b) {
                b.Format("e:uint8_t[0] nothing;");
                b.Format("a:uint64_t timestamp;e[65535] x;float[65535] big;");
                b.Add(0, 1, "a");
              }),
              {"larger than 65535 bytes"});
  ExpectError(with([](ULogBuilder& b) { b.Info("int32_t x", "12345"); }), {"byte 16", "has 5 bytes, expected 4"});
  ExpectError(with([](ULogBuilder& b) { b.Message('I', "\x30 too short"); }), {"overruns its message"});
  ExpectError(with([](ULogBuilder& b) { b.Parameter("double X", ULogBuilder::Pod(1.0)); }),
              {"ULog parameters are int32_t or float"});
  ExpectError(with([](ULogBuilder& b) { b.FlagBits(2, {}); }), {"unknown incompatible flag"});
  ExpectError(with([](ULogBuilder& b) {
                b.Format("a:uint64_t timestamp;");
                b.Add(0, 1, "a");
                b.Data(2, ULogBuilder::Pod<uint64_t>(1));
              }),
              {"msg_id 2"});
}

}  // namespace
}  // namespace rotorid
