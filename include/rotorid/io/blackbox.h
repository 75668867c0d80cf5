#pragma once

// Betaflight / INAV / Cleanflight blackbox logs (.BBL, .BFL, .TXT), decoded from the format's
// documentation (docs/blackbox.md): "H name:value" header lines, then I (intra) and P (inter)
// main frames, S (slow), G (GPS), H (GPS home) and E (event) frames, each field decoded by its
// encoding and then its predictor. One file may hold several logs (one per arming); each starts
// with the "H Product:Blackbox flight data recorder by Nicholas Sherlock" line.
//
// Damage is contained: a frame whose bytes do not decode, or after which no valid frame marker
// follows, is dropped; the decoder scans forward to the next frame marker and resumes main frames
// at the next I-frame. Every dropped stretch is listed in BlackboxLog::damage.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace rotorid {

// One frame type's fields as the header declares them ("H Field <type> name/signed/predictor/
// encoding"). P-frames share the I-frame's names and signedness.
struct BlackboxFieldDefs {
  std::vector<std::string> names;
  std::vector<int> is_signed;
  std::vector<int> predictor;
  std::vector<int> encoding;

  int size() const { return static_cast<int>(names.size()); }
  // Index of a field by its exact name, or -1.
  int Find(const std::string& name) const;
};

// Decoded frames of one type: row-major, values[frame * num_fields + field]. Signed fields hold
// their int32 value, unsigned ones their uint32 value.
struct BlackboxFrames {
  std::vector<std::string> names;
  std::vector<std::int64_t> values;
  // For S/G/H frames: the number of main frames decoded before this one (its place in time).
  std::vector<int> main_index;

  int num_fields() const { return static_cast<int>(names.size()); }
  int num_frames() const { return names.empty() ? 0 : static_cast<int>(values.size() / names.size()); }
  int Find(const std::string& name) const;
  std::int64_t at(int frame, int field) const { return values[static_cast<size_t>(frame) * names.size() + field]; }
};

enum class BlackboxEventType {
  kSyncBeep = 0,
  kAutotuneCycleStart = 10,
  kAutotuneCycleResult = 11,
  kAutotuneTargets = 12,
  kInflightAdjustment = 13,
  kLoggingResume = 14,
  kDisarm = 15,
  kGtuneCycleResult = 20,
  kFlightMode = 30,
  kImuFailure = 40,
  kLogEnd = 255,
};

// "sync beep", "logging resume", "disarm", "flight mode", "log end", ...
const char* ToString(BlackboxEventType type);

struct BlackboxEvent {
  BlackboxEventType type = BlackboxEventType::kSyncBeep;
  std::vector<std::int64_t> data;  // the event's values in order (e.g. resume: iteration, time_us)
  int main_index = 0;              // main frames decoded before it
};

// A stretch of the file that did not decode.
struct BlackboxDamage {
  std::size_t offset = 0;  // byte offset in the file where the bad frame started
  std::size_t bytes = 0;   // bytes skipped until the next frame that decoded
  std::string what;        // e.g. "P-frame: no frame marker after it", "file ends inside an I-frame"
};

struct BlackboxLog {
  int index = 1;                              // 1-based position in the file
  std::size_t offset = 0;                     // byte offset of its first header line
  std::map<std::string, std::string> header;  // every "H name:value" line (field lists included)
  BlackboxFieldDefs i_defs, p_defs, s_defs, g_defs, h_defs;
  BlackboxFrames main;              // I- and P-frames in file order
  std::vector<char> main_is_intra;  // per main frame: 1 for an I-frame
  BlackboxFrames slow, gps, home;
  std::vector<BlackboxEvent> events;
  std::vector<BlackboxDamage> damage;
  int i_frames = 0, p_frames = 0;
  // P-frames decoded without a valid reference frame (after damage, before the next I-frame).
  int p_frames_without_reference = 0;
  bool ended_cleanly = false;  // a "log end" event closes it
  // Why the header cannot be used (no frames are then decoded), or "".
  std::string header_error;

  // Header value, or `fallback` when the header lacks it.
  std::string Header(const std::string& name, const std::string& fallback = "") const;
  // Header value as an integer (first of a comma list), or `fallback`.
  long HeaderInt(const std::string& name, long fallback) const;
  // One line: frame counts per type, events, damage.
  std::string Summary() const;
};

// The bytes of a blackbox file start with a header line "H Product:Blackbox ..." (possibly after
// a few bytes of padding written by some loggers).
bool LooksLikeBlackbox(const std::string& head);

// Decodes every log in `bytes`. `source` names the file in messages. Throws rotorid::Error when
// there is no log header at all or a log's header lacks the I-frame field definitions; damage
// inside a log is reported in BlackboxLog::damage instead.
std::vector<BlackboxLog> DecodeBlackbox(const std::string& bytes, const std::string& source);
// Reads and decodes a file.
std::vector<BlackboxLog> ReadBlackboxFile(const std::string& path);

}  // namespace rotorid
