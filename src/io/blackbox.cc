#include "rotorid/io/blackbox.h"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <utility>

#include "rotorid/core/error.h"

namespace rotorid {
namespace internal {
namespace {

constexpr char kLogStart[] = "H Product:Blackbox flight data recorder by Nicholas Sherlock";
constexpr char kLogEndText[] = "End of log";
// Consecutive main frames further apart than this are taken as damage, as a real logger never
// skips that much without a "logging resume" event.
constexpr std::int64_t kMaxIterationJump = 5000 * 10;
constexpr std::int64_t kMaxTimeJumpUs = 10 * 1000000;
// A header line longer than this is damage (real ones reach a few kB: long field lists).
constexpr std::size_t kMaxHeaderLine = 1 << 16;

enum Encoding {
  kSignedVb = 0,
  kUnsignedVb = 1,
  kNeg14Bit = 3,
  kTag8_8Svb = 6,
  kTag2_3S32 = 7,
  kTag8_4S16 = 8,
  kNull = 9,
  kTag2_3SVariable = 10,
};

enum Predictor {
  kZero = 0,
  kPrevious = 1,
  kStraightLine = 2,
  kAverage2 = 3,
  kMinThrottle = 4,
  kMotor0 = 5,
  kIncrement = 6,
  kHomeCoord = 7,
  k1500 = 8,
  kVbatRef = 9,
  kLastMainFrameTime = 10,
  kMinMotor = 11,
};

bool IsKnownEncoding(int e) {
  return e == kSignedVb || e == kUnsignedVb || e == kNeg14Bit || (e >= kTag8_8Svb && e <= kTag2_3SVariable);
}

bool IsFrameMarker(char c) { return c == 'I' || c == 'P' || c == 'S' || c == 'G' || c == 'H' || c == 'E'; }

std::int32_t SignExtend(std::uint32_t value, int bits) {
  const std::uint32_t mask = bits >= 32 ? 0xffffffffu : (1u << bits) - 1;
  const std::uint32_t sign = 1u << (bits - 1);
  return static_cast<std::int32_t>(((value & mask) ^ sign) - sign);
}

// Reads the format's primitives from [pos, end). Reading past the end, or a malformed variable
// byte, sets a flag and yields zeros, so a frame decoder runs to its end and is then rejected.
class ByteReader {
 public:
  ByteReader(const std::string& bytes, std::size_t pos, std::size_t end) : bytes_(bytes), pos_(pos), end_(end) {}

  std::size_t pos() const { return pos_; }
  bool out_of_bytes() const { return out_of_bytes_; }
  bool malformed() const { return malformed_; }
  void SetMalformed() { malformed_ = true; }

  std::uint8_t Byte() {
    if (pos_ >= end_) {
      out_of_bytes_ = true;
      return 0;
    }
    return static_cast<std::uint8_t>(bytes_[pos_++]);
  }
  std::uint32_t UnsignedVb() {
    std::uint32_t value = 0;
    for (int shift = 0; shift < 35; shift += 7) {
      const std::uint8_t b = Byte();
      value |= static_cast<std::uint32_t>(b & 0x7f) << shift;
      if ((b & 0x80) == 0) return value;
    }
    malformed_ = true;  // more than 5 bytes: not a 32-bit value
    return 0;
  }
  std::int32_t SignedVb() {
    const std::uint32_t u = UnsignedVb();  // zig-zag
    return static_cast<std::int32_t>((u >> 1) ^ (~(u & 1) + 1));
  }
  std::uint32_t LittleEndian(int num_bytes) {
    std::uint32_t value = 0;
    for (int i = 0; i < num_bytes; ++i) value |= static_cast<std::uint32_t>(Byte()) << (8 * i);
    return value;
  }
  bool Text(const char* text) {
    for (const char* c = text; *c; ++c)
      if (Byte() != static_cast<std::uint8_t>(*c)) return false;
    return true;
  }

 private:
  const std::string& bytes_;
  std::size_t pos_;
  std::size_t end_;
  bool out_of_bytes_ = false;
  bool malformed_ = false;
};

// Three values under a 2-bit selector: 2-bit fields, 4-bit, 6-bit, or 8/16/24/32-bit each.
// `lead` is the selector byte, already read.
void ReadTag2_3S32(ByteReader& in, std::uint8_t lead, std::int64_t out[3]) {
  switch (lead >> 6) {
    case 0:
      for (int i = 0; i < 3; ++i) out[i] = SignExtend(lead >> (4 - 2 * i), 2);
      break;
    case 1: {
      const std::uint8_t b = in.Byte();
      out[0] = SignExtend(lead, 4);
      out[1] = SignExtend(b >> 4, 4);
      out[2] = SignExtend(b, 4);
      break;
    }
    case 2:
      out[0] = SignExtend(lead, 6);
      out[1] = SignExtend(in.Byte(), 6);
      out[2] = SignExtend(in.Byte(), 6);
      break;
    default:
      for (int i = 0; i < 3; ++i) {
        const int num_bytes = ((lead >> (2 * i)) & 3) + 1;
        out[i] = SignExtend(in.LittleEndian(num_bytes), 8 * num_bytes);
      }
  }
}

// Like tag2_3s32, with 5-5-4 and 8-7-7 bit packings (MSB first after the selector) in place of
// 4-4-4 and 6-6-6.
void ReadTag2_3SVariable(ByteReader& in, std::int64_t out[3]) {
  const std::uint8_t lead = in.Byte();
  const int selector = lead >> 6;
  if (selector == 0 || selector == 3) {
    ReadTag2_3S32(in, lead, out);  // same 2-bit and 8/16/24/32-bit cases
    return;
  }
  const int widths[2][3] = {{5, 5, 4}, {8, 7, 7}};
  const int* width = widths[selector - 1];
  std::uint32_t bits = lead & 0x3f;
  const int extra_bytes = selector;
  for (int i = 0; i < extra_bytes; ++i) bits = (bits << 8) | in.Byte();
  int remaining = 6 + 8 * extra_bytes;
  for (int i = 0; i < 3; ++i) {
    remaining -= width[i];
    out[i] = SignExtend(bits >> remaining, width[i]);
  }
}

// Four values under a selector byte (2 bits each: zero, 4-bit, 8-bit, 16-bit). Data version 2
// packs them as a stream of nibbles, high nibble first; version 1 pairs two 4-bit values in one
// byte (low nibble first) and keeps 8- and 16-bit values byte aligned.
void ReadTag8_4S16(ByteReader& in, int data_version, std::int64_t out[4]) {
  std::uint8_t selector = in.Byte();
  if (data_version < 2) {
    for (int i = 0; i < 4; ++i, selector >>= 2) {
      switch (selector & 3) {
        case 0:
          out[i] = 0;
          break;
        case 1: {
          const std::uint8_t b = in.Byte();
          out[i] = SignExtend(b, 4);
          if (++i < 4) out[i] = SignExtend(b >> 4, 4);
          selector >>= 2;
          break;
        }
        case 2:
          out[i] = SignExtend(in.Byte(), 8);
          break;
        default:
          out[i] = SignExtend(in.LittleEndian(2), 16);
      }
    }
    return;
  }
  std::uint32_t pending = 0;  // the low nibble of the last byte read, when half used
  bool half_used = false;
  const auto nibbles = [&](int count) {
    std::uint32_t value = 0;
    for (int k = 0; k < count; ++k) {
      if (half_used) {
        value = (value << 4) | pending;
      } else {
        const std::uint8_t b = in.Byte();
        value = (value << 4) | (b >> 4);
        pending = b & 0x0f;
      }
      half_used = !half_used;
    }
    return value;
  };
  for (int i = 0; i < 4; ++i, selector >>= 2) {
    const int kind = selector & 3;
    out[i] = kind == 0 ? 0 : SignExtend(nibbles(kind == 3 ? 4 : kind), kind == 3 ? 16 : 4 * kind);
  }
}

// Index of the first field after the run of fields sharing field `begin`'s encoding, at most
// `max_count` long.
int RunEnd(const std::vector<int>& encoding, int begin, int max_count) {
  int end = begin + 1;
  while (end < static_cast<int>(encoding.size()) && end - begin < max_count && encoding[end] == encoding[begin]) ++end;
  return end;
}

// Decodes the encoded (pre-prediction) values of one frame into raw[0..n).
void ReadEncodedFields(ByteReader& in, const std::vector<int>& encoding, int data_version, std::int64_t* raw) {
  const int n = static_cast<int>(encoding.size());
  std::int64_t group[4];
  for (int i = 0; i < n;) {
    switch (encoding[i]) {
      case kSignedVb:
        raw[i++] = in.SignedVb();
        break;
      case kUnsignedVb:
        raw[i++] = in.UnsignedVb();
        break;
      case kNeg14Bit:
        raw[i++] = -SignExtend(in.UnsignedVb(), 14);
        break;
      case kNull:
        raw[i++] = 0;
        break;
      case kTag8_8Svb: {
        const int end = RunEnd(encoding, i, 8);
        if (end - i == 1) {
          raw[i++] = in.SignedVb();
          break;
        }
        const std::uint8_t present = in.Byte();
        for (int k = 0; i < end; ++i, ++k) raw[i] = (present >> k) & 1 ? in.SignedVb() : 0;
        break;
      }
      case kTag2_3S32:
      case kTag2_3SVariable:
      case kTag8_4S16: {
        const int count = encoding[i] == kTag8_4S16 ? 4 : 3;
        if (encoding[i] == kTag8_4S16)
          ReadTag8_4S16(in, data_version, group);
        else if (encoding[i] == kTag2_3S32)
          ReadTag2_3S32(in, in.Byte(), group);
        else
          ReadTag2_3SVariable(in, group);
        for (int k = 0; k < count && i < n; ++k) raw[i++] = group[k];
        break;
      }
      default:
        in.SetMalformed();
        return;  // the header check rejects unknown encodings first
    }
  }
}

// The header values the predictors refer to, and the main-frame frequency for INCREMENT.
struct PredictorContext {
  std::int64_t min_throttle = 0, min_motor = 0, vbat_ref = 0;
  int motor0_field = -1;     // main-frame index of motor[0]
  int iteration_field = -1;  // loopIteration
  int time_field = -1;       // time
  std::int64_t i_interval = 32, p_num = 1, p_denom = 1;
  std::int64_t home[2] = {0, 0};
  std::int64_t last_main_time = 0;
  std::int64_t last_main_iteration = -1;

  // Whether the logger writes a main frame at this loop iteration.
  bool HasFrame(std::int64_t iteration) const { return ((iteration % i_interval) + p_num - 1) % p_denom < p_num; }
  // Loop iterations from the last main frame to the next one it writes.
  std::int64_t IterationStep() const {
    if (last_main_iteration < 0) return 1;
    std::int64_t step = 1;
    while (!HasFrame(last_main_iteration + step) && step < p_denom * i_interval) ++step;
    return step;
  }
};

std::int64_t Wrap32(std::int64_t value, bool is_signed) {
  const auto u = static_cast<std::uint32_t>(static_cast<std::uint64_t>(value));
  return is_signed ? static_cast<std::int64_t>(static_cast<std::int32_t>(u)) : static_cast<std::int64_t>(u);
}

// Applies the predictors to raw values: out[i] = raw[i] + prediction, wrapped to 32 bits.
// `prev` and `prev2` are the last two frames of the same stream (null when absent).
void ApplyPredictors(const BlackboxFieldDefs& defs, const std::vector<int>& is_signed, const PredictorContext& ctx,
                     const std::int64_t* prev, const std::int64_t* prev2, const std::int64_t* raw, std::int64_t* out) {
  int home_coords_seen = 0;
  for (int i = 0; i < defs.size(); ++i) {
    const bool sign = is_signed[i] != 0;
    const std::int64_t p1 = prev ? prev[i] : 0;
    const std::int64_t p2 = prev2 ? prev2[i] : p1;
    std::int64_t prediction = 0;
    switch (defs.predictor[i]) {
      case kZero:
        break;
      case kPrevious:
        prediction = p1;
        break;
      case kStraightLine:
        prediction = 2 * p1 - p2;
        break;
      case kAverage2:
        prediction = (p1 + p2) / 2;
        break;  // truncates toward zero, like the logger
      case kMinThrottle:
        prediction = ctx.min_throttle;
        break;
      case kMotor0:
        prediction = ctx.motor0_field >= 0 && ctx.motor0_field < i ? out[ctx.motor0_field] : 0;
        break;
      case kIncrement:
        prediction = p1 + (prev ? ctx.IterationStep() : 1);
        break;
      case kHomeCoord:
        prediction = ctx.home[std::min(home_coords_seen++, 1)];
        break;
      case k1500:
        prediction = 1500;
        break;
      case kVbatRef:
        prediction = ctx.vbat_ref;
        break;
      case kLastMainFrameTime:
        prediction = ctx.last_main_time;
        break;
      case kMinMotor:
        prediction = ctx.min_motor;
        break;
      default:
        break;  // the header check rejects unknown predictors first
    }
    out[i] = Wrap32(raw[i] + prediction, sign);
  }
}

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream stream(text);
  while (std::getline(stream, part, ',')) parts.push_back(part);
  if (!text.empty() && text.back() == ',') parts.emplace_back();
  return parts;
}

std::vector<int> SplitInts(const std::string& text) {
  std::vector<int> values;
  for (const std::string& part : SplitCommas(text)) {
    try {
      values.push_back(std::stoi(part));
    } catch (const std::exception&) {
      values.push_back(-1);  // rejected by the header check as an unknown encoding/predictor
    }
  }
  return values;
}

long ParseLong(const std::string& text, long fallback) {
  try {
    std::size_t used = 0;
    const long value = std::stol(text, &used, 0);
    return used > 0 ? value : fallback;
  } catch (const std::exception&) {
    return fallback;
  }
}

// Reads "Field <type> name/signed/predictor/encoding" for one frame type. Returns an error
// message, or "" (also when the header has no fields of this type).
std::string ReadFieldDefs(const std::map<std::string, std::string>& header, char type,
                          const BlackboxFieldDefs* names_from, BlackboxFieldDefs* defs) {
  const std::string prefix = std::string("Field ") + type + " ";
  const auto get = [&](const char* what) -> const std::string* {
    const auto it = header.find(prefix + what);
    return it == header.end() ? nullptr : &it->second;
  };
  if (names_from) {
    defs->names = names_from->names;
    defs->is_signed = names_from->is_signed;
  } else {
    if (!get("name")) return "";
    defs->names = SplitCommas(*get("name"));
    defs->is_signed = get("signed") ? SplitInts(*get("signed")) : std::vector<int>(defs->names.size(), 0);
  }
  if (!get("predictor") || !get("encoding")) {
    if (names_from && !get("predictor") && !get("encoding")) return "";
    return std::string("'") + prefix + "predictor' or '" + prefix + "encoding' missing";
  }
  defs->predictor = SplitInts(*get("predictor"));
  defs->encoding = SplitInts(*get("encoding"));
  const size_t n = defs->names.size();
  if (defs->is_signed.size() != n || defs->predictor.size() != n || defs->encoding.size() != n)
    return std::string(1, type) + "-frame field lists differ in length (" + std::to_string(n) + " names)";
  for (size_t i = 0; i < n; ++i) {
    if (!IsKnownEncoding(defs->encoding[i]))
      return std::string(1, type) + "-frame field '" + defs->names[i] + "': unknown encoding " +
             std::to_string(defs->encoding[i]);
    if (defs->predictor[i] < kZero || defs->predictor[i] > kMinMotor)
      return std::string(1, type) + "-frame field '" + defs->names[i] + "': unknown predictor " +
             std::to_string(defs->predictor[i]);
  }
  return "";
}

std::size_t NextMarker(const std::string& bytes, std::size_t pos, std::size_t end) {
  while (pos < end && !IsFrameMarker(bytes[pos])) ++pos;
  return pos;
}

// Decodes one log: bytes [begin, end) of the file, starting at its first header line.
class LogDecoder {
 public:
  LogDecoder(const std::string& bytes, std::size_t begin, std::size_t end, BlackboxLog* log)
      : bytes_(bytes), begin_(begin), end_(end), log_(*log) {}

  void Run() {
    const std::size_t data_begin = ReadHeader();
    log_.header_error = SetUpFields();
    if (log_.header_error.empty()) DecodeFrames(data_begin);
  }

 private:
  enum class Result { kOk, kOutOfBytes, kMalformed, kLogEnd };

  // A decoded frame waiting for the check that a frame marker follows it.
  struct Pending {
    char type = 0;
    std::vector<std::int64_t> values;
    BlackboxEvent event;
  };

  std::size_t ReadHeader() {
    std::size_t pos = begin_;
    while (pos + 1 < end_ && bytes_[pos] == 'H' && bytes_[pos + 1] == ' ') {
      const std::size_t limit = std::min(end_, pos + kMaxHeaderLine);
      std::size_t eol = pos;
      while (eol < limit && bytes_[eol] != '\n') ++eol;
      std::string line = bytes_.substr(pos + 2, eol - pos - 2);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos) log_.header[line.substr(0, colon)] = line.substr(colon + 1);
      pos = eol < end_ ? eol + 1 : eol;
    }
    return pos;
  }

  std::string SetUpFields() {
    if (std::string e = ReadFieldDefs(log_.header, 'I', nullptr, &log_.i_defs); !e.empty()) return e;
    if (log_.i_defs.size() == 0) return "no 'Field I name' header line";
    if (std::string e = ReadFieldDefs(log_.header, 'P', &log_.i_defs, &log_.p_defs); !e.empty()) return e;
    if (log_.p_defs.predictor.empty()) return "no 'Field P predictor' header line";
    for (auto [type, defs] : {std::pair{'S', &log_.s_defs}, {'G', &log_.g_defs}, {'H', &log_.h_defs}})
      if (std::string e = ReadFieldDefs(log_.header, type, nullptr, defs); !e.empty()) return e;
    log_.main.names = log_.i_defs.names;
    log_.slow.names = log_.s_defs.names;
    log_.gps.names = log_.g_defs.names;
    log_.home.names = log_.h_defs.names;
    data_version_ = static_cast<int>(log_.HeaderInt("Data version", 2));
    ctx_.min_throttle = log_.HeaderInt("minthrottle", 0);
    ctx_.min_motor = log_.HeaderInt("motorOutput", 0);
    ctx_.vbat_ref = log_.HeaderInt("vbatref", 0);
    ctx_.motor0_field = log_.i_defs.Find("motor[0]");
    ctx_.iteration_field = log_.i_defs.Find("loopIteration");
    ctx_.time_field = log_.i_defs.Find("time");
    ctx_.i_interval = std::max(1L, log_.HeaderInt("I interval", 32));
    const std::string p_interval = log_.Header("P interval", "1");
    if (const std::size_t slash = p_interval.find('/'); slash != std::string::npos) {
      ctx_.p_num = std::max(1L, ParseLong(p_interval.substr(0, slash), 1));
      ctx_.p_denom = std::max(1L, ParseLong(p_interval.substr(slash + 1), 1));
    } else {
      ctx_.p_denom = std::max(1L, ParseLong(p_interval, 1));  // Betaflight 4: every N-th iteration
    }
    ctx_.i_interval = std::min<std::int64_t>(ctx_.i_interval, 1 << 16);
    ctx_.p_denom = std::min<std::int64_t>(ctx_.p_denom, 1 << 16);
    for (const auto* defs : {&log_.i_defs, &log_.p_defs})
      for (int i = 0; i < defs->size(); ++i)
        if (defs->predictor[i] == kMotor0 && (ctx_.motor0_field < 0 || ctx_.motor0_field >= i))
          return "field '" + defs->names[i] + "' is predicted from motor[0], which does not precede it";
    return "";
  }

  void DecodeFrames(std::size_t pos) {
    bool damaged = false;
    BlackboxDamage damage;
    const auto begin_damage = [&](std::size_t at, const std::string& what) {
      if (damaged) return;
      damaged = true;
      damage = {at, 0, what};
    };
    const auto end_damage = [&](std::size_t at) {
      if (!damaged) return;
      damage.bytes = at - damage.offset;
      log_.damage.push_back(damage);
      damaged = false;
    };
    while (pos < end_) {
      const char type = bytes_[pos];
      if (!IsFrameMarker(type)) {
        begin_damage(pos, "byte " + std::to_string(static_cast<unsigned char>(type)) + " where a frame should start");
        pos = NextMarker(bytes_, pos + 1, end_);
        continue;
      }
      ByteReader in(bytes_, pos + 1, end_);
      Pending frame;
      frame.type = type;
      std::string what;
      Result result = Decode(in, &frame, &what);
      if (result == Result::kOutOfBytes) {
        begin_damage(pos,
                     std::string("file ends inside ") + (type == 'I' || type == 'E' ? "an " : "a ") + type + "-frame");
        pos = end_;
        break;
      }
      if (result == Result::kOk && in.pos() < end_ && !IsFrameMarker(bytes_[in.pos()])) {
        result = Result::kMalformed;
        what = "no frame marker after it";
      }
      if (result == Result::kOk && !Commit(&frame, &what)) result = Result::kMalformed;
      if (result == Result::kMalformed) {
        if (type == 'I' || type == 'P') main_valid_ = false;
        begin_damage(pos, std::string(1, type) + "-frame: " + what);
        pos = NextMarker(bytes_, pos + 1, end_);
        continue;
      }
      end_damage(pos);
      pos = in.pos();
      if (result == Result::kLogEnd) {
        log_.events.push_back(frame.event);
        log_.ended_cleanly = true;
        break;
      }
    }
    end_damage(pos);
  }

  Result Decode(ByteReader& in, Pending* frame, std::string* what) {
    switch (frame->type) {
      case 'I':
        return DecodeFields(in, log_.i_defs, nullptr, nullptr, frame);
      case 'P': {
        const int n = log_.main.num_frames();
        const std::int64_t* prev = n > 0 && main_valid_ ? Row(log_.main, n - 1) : nullptr;
        const std::int64_t* prev2 = prev && history_ >= 2 ? Row(log_.main, n - 2) : prev;
        return DecodeFields(in, log_.p_defs, prev, prev2, frame);
      }
      case 'S':
        return DecodeOther(in, log_.s_defs, log_.slow, frame, what);
      case 'G':
        return DecodeOther(in, log_.g_defs, log_.gps, frame, what);
      case 'H':
        return DecodeOther(in, log_.h_defs, log_.home, frame, what);
      default:
        return DecodeEvent(in, &frame->event, what);
    }
  }

  static const std::int64_t* Row(const BlackboxFrames& frames, int index) {
    return frames.values.data() + static_cast<std::size_t>(index) * frames.names.size();
  }

  Result DecodeOther(ByteReader& in, const BlackboxFieldDefs& defs, const BlackboxFrames& frames, Pending* frame,
                     std::string* what) {
    if (defs.size() == 0) {
      *what = "the header defines no fields for this frame type";
      return Result::kMalformed;
    }
    const int n = frames.num_frames();
    const std::int64_t* prev = n > 0 ? Row(frames, n - 1) : nullptr;
    return DecodeFields(in, defs, prev, prev, frame);
  }

  Result DecodeFields(ByteReader& in, const BlackboxFieldDefs& defs, const std::int64_t* prev,
                      const std::int64_t* prev2, Pending* frame) {
    raw_.assign(defs.size(), 0);
    frame->values.assign(defs.size(), 0);
    ReadEncodedFields(in, defs.encoding, data_version_, raw_.data());
    if (in.out_of_bytes()) return Result::kOutOfBytes;
    if (in.malformed()) return Result::kMalformed;
    const bool is_main = frame->type == 'I' || frame->type == 'P';
    ApplyPredictors(defs, is_main ? log_.i_defs.is_signed : defs.is_signed, ctx_, prev, prev2, raw_.data(),
                    frame->values.data());
    return Result::kOk;
  }

  Result DecodeEvent(ByteReader& in, BlackboxEvent* event, std::string* what) {
    const std::uint8_t type = in.Byte();
    event->type = static_cast<BlackboxEventType>(type);
    event->main_index = log_.main.num_frames();
    auto& data = event->data;
    switch (type) {
      case 0:   // sync beep: time
      case 15:  // disarm: reason
        data.push_back(in.UnsignedVb());
        break;
      case 13: {  // in-flight adjustment: function, then a float (function >= 128) or a value
        const std::uint8_t function = in.Byte();
        data.push_back(function);
        data.push_back(function & 0x80 ? static_cast<std::int64_t>(in.LittleEndian(4)) : in.SignedVb());
        break;
      }
      case 14:  // logging resume: loop iteration, time (us)
      case 30:  // flight mode: new flags, old flags
        data.push_back(in.UnsignedVb());
        data.push_back(in.UnsignedVb());
        break;
      case 255:
        if (!in.Text(kLogEndText) || in.Byte() != 0) {
          if (in.out_of_bytes()) return Result::kOutOfBytes;
          *what = "log-end event without its 'End of log' text";
          return Result::kMalformed;
        }
        return Result::kLogEnd;
      default:
        *what = "unknown event type " + std::to_string(type);
        return Result::kMalformed;
    }
    if (in.out_of_bytes()) return Result::kOutOfBytes;
    return in.malformed() ? Result::kMalformed : Result::kOk;
  }

  // Stores a decoded frame; false (with the reason) when a main frame's iteration or time is
  // implausible after the previous one.
  bool Commit(Pending* frame, std::string* what) {
    switch (frame->type) {
      case 'I':
      case 'P':
        return CommitMain(frame, what);
      case 'S':
        Append(&log_.slow, frame->values);
        break;
      case 'G':
        Append(&log_.gps, frame->values);
        break;
      case 'H':
        Append(&log_.home, frame->values);
        for (int k = 0; k < 2 && k < static_cast<int>(frame->values.size()); ++k) ctx_.home[k] = frame->values[k];
        break;
      default:
        if (frame->event.type == BlackboxEventType::kLoggingResume) {
          ctx_.last_main_iteration = frame->event.data[0];
          ctx_.last_main_time = frame->event.data[1];
        }
        log_.events.push_back(frame->event);
    }
    return true;
  }

  void Append(BlackboxFrames* frames, const std::vector<std::int64_t>& values) {
    frames->values.insert(frames->values.end(), values.begin(), values.end());
    frames->main_index.push_back(log_.main.num_frames());
  }

  bool CommitMain(Pending* frame, std::string* what) {
    const bool intra = frame->type == 'I';
    if (!intra && !main_valid_) {
      ++log_.p_frames_without_reference;  // decodes, but its reference was lost
      return true;
    }
    const auto& v = frame->values;
    const std::int64_t iteration = ctx_.iteration_field >= 0 ? v[ctx_.iteration_field] : -1;
    const std::int64_t time = ctx_.time_field >= 0 ? v[ctx_.time_field] : -1;
    if (ctx_.last_main_iteration >= 0 && iteration >= 0 &&
        (iteration < ctx_.last_main_iteration || iteration > ctx_.last_main_iteration + kMaxIterationJump)) {
      *what = "loop iteration " + std::to_string(iteration) + " after " + std::to_string(ctx_.last_main_iteration);
      return false;
    }
    if (have_time_ && time >= 0 && (time < ctx_.last_main_time || time > ctx_.last_main_time + kMaxTimeJumpUs)) {
      *what = "time " + std::to_string(time) + " us after " + std::to_string(ctx_.last_main_time) + " us";
      return false;
    }
    log_.main.values.insert(log_.main.values.end(), v.begin(), v.end());
    log_.main_is_intra.push_back(intra ? 1 : 0);
    ++(intra ? log_.i_frames : log_.p_frames);
    history_ = intra ? 1 : std::min(history_ + 1, 2);
    main_valid_ = true;
    if (iteration >= 0) ctx_.last_main_iteration = iteration;
    if (time >= 0) {
      ctx_.last_main_time = time;
      have_time_ = true;
    }
    return true;
  }

  const std::string& bytes_;
  std::size_t begin_, end_;
  BlackboxLog& log_;
  PredictorContext ctx_;
  int data_version_ = 2;
  bool main_valid_ = false;  // the last main frame decoded with a valid reference
  bool have_time_ = false;
  int history_ = 0;  // valid main frames since the last I-frame, at most 2
  std::vector<std::int64_t> raw_;
};

}  // namespace
}  // namespace internal

int BlackboxFieldDefs::Find(const std::string& name) const {
  for (int i = 0; i < size(); ++i)
    if (names[i] == name) return i;
  return -1;
}

int BlackboxFrames::Find(const std::string& name) const {
  for (int i = 0; i < num_fields(); ++i)
    if (names[i] == name) return i;
  return -1;
}

const char* ToString(BlackboxEventType type) {
  switch (type) {
    case BlackboxEventType::kSyncBeep:
      return "sync beep";
    case BlackboxEventType::kAutotuneCycleStart:
      return "autotune cycle start";
    case BlackboxEventType::kAutotuneCycleResult:
      return "autotune cycle result";
    case BlackboxEventType::kAutotuneTargets:
      return "autotune targets";
    case BlackboxEventType::kInflightAdjustment:
      return "in-flight adjustment";
    case BlackboxEventType::kLoggingResume:
      return "logging resume";
    case BlackboxEventType::kDisarm:
      return "disarm";
    case BlackboxEventType::kGtuneCycleResult:
      return "gtune cycle result";
    case BlackboxEventType::kFlightMode:
      return "flight mode";
    case BlackboxEventType::kImuFailure:
      return "IMU failure";
    case BlackboxEventType::kLogEnd:
      return "log end";
  }
  return "unknown event";
}

std::string BlackboxLog::Header(const std::string& name, const std::string& fallback) const {
  const auto it = header.find(name);
  return it == header.end() ? fallback : it->second;
}

long BlackboxLog::HeaderInt(const std::string& name, long fallback) const {
  const auto it = header.find(name);
  if (it == header.end()) return fallback;
  return internal::ParseLong(it->second.substr(0, it->second.find(',')), fallback);
}

std::string BlackboxLog::Summary() const {
  std::size_t damaged_bytes = 0;
  for (const BlackboxDamage& d : damage) damaged_bytes += d.bytes;
  std::string s = "log " + std::to_string(index) + ": ";
  if (!header_error.empty()) return s + "unreadable header (" + header_error + ")";
  s += std::to_string(main.num_frames()) + " main frames (" + std::to_string(i_frames) + " I, " +
       std::to_string(p_frames) + " P), " + std::to_string(slow.num_frames()) + " S, " +
       std::to_string(gps.num_frames()) + " G, " + std::to_string(home.num_frames()) + " H, " +
       std::to_string(events.size()) + " events; " + std::to_string(damage.size()) + " damaged stretches (" +
       std::to_string(damaged_bytes) + " bytes)";
  if (p_frames_without_reference > 0)
    s += ", " + std::to_string(p_frames_without_reference) + " P-frames lost for want of a reference";
  return s + (ended_cleanly ? "; ends with a log-end event" : "; no log-end event");
}

bool LooksLikeBlackbox(const std::string& head) { return head.find(internal::kLogStart) != std::string::npos; }

std::vector<BlackboxLog> DecodeBlackbox(const std::string& bytes, const std::string& source) {
  std::vector<std::size_t> starts;
  for (std::size_t at = bytes.find(internal::kLogStart); at != std::string::npos;
       at = bytes.find(internal::kLogStart, at + 1))
    starts.push_back(at);
  if (starts.empty()) throw Error(source + ": not a blackbox log (no '" + std::string(internal::kLogStart) + "' line)");
  std::vector<BlackboxLog> logs(starts.size());
  for (std::size_t k = 0; k < starts.size(); ++k) {
    logs[k].index = static_cast<int>(k) + 1;
    logs[k].offset = starts[k];
    const std::size_t end = k + 1 < starts.size() ? starts[k + 1] : bytes.size();
    internal::LogDecoder(bytes, starts[k], end, &logs[k]).Run();
  }
  return logs;
}

std::vector<BlackboxLog> ReadBlackboxFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  std::ostringstream content;
  content << in.rdbuf();
  return DecodeBlackbox(content.str(), path);
}

}  // namespace rotorid
