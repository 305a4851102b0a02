#include "plsa/can/candump_log.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "plsa/core/median.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::can {

namespace {

[[noreturn]] void rejectLine(const std::string& source, std::size_t line, const std::string& why) {
  throw std::runtime_error(source + ":" + std::to_string(line) + ": " + why);
}

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool allHex(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return hexDigit(c) >= 0; });
}

// "(1436509052.249713)": seconds and up to nine decimals, as candump writes them.
double timeStamp(const std::string& field, const std::string& source, std::size_t line) {
  const auto dot = field.find('.');
  const bool shaped = field.size() >= 5 && field.front() == '(' && field.back() == ')' && dot != std::string::npos &&
                      dot > 1 && dot + 2 < field.size() && dot + 11 >= field.size();
  const std::string whole = shaped ? field.substr(1, dot - 1) : "", part = shaped ? field.substr(dot + 1) : "";
  const auto digits = [](const std::string& s) {
    return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  if (!shaped || !digits(whole) || !digits(part.substr(0, part.size() - 1)) || whole.size() > 12)
    rejectLine(source, line, "time stamp '" + field + "' is not (seconds.fraction) as candump writes it");
  return std::strtod(field.substr(1, field.size() - 2).c_str(), nullptr);
}

// "123#11223344", "12345678#...", "123#R", "123##1...": the frame itself.
void frameField(const std::string& field, CandumpLine& out, const std::string& source, std::size_t line) {
  const auto hash = field.find('#');
  const std::string id = field.substr(0, hash);
  if (hash == std::string::npos || !allHex(id) || (id.size() != 3 && id.size() != 8))
    rejectLine(source, line, "frame '" + field + "' is not id#data (3 or 8 hex digits of id)");
  std::string data = field.substr(hash + 1);
  if (id.size() == 8) {
    out.kind = CandumpLine::Kind::kExtended;
    return;
  }
  if (!data.empty() && data[0] == '#') {
    out.kind = CandumpLine::Kind::kFd;
    return;
  }
  if (!data.empty() && data[0] == 'R') {
    out.kind = CandumpLine::Kind::kRemote;
    return;
  }
  const auto dlc_suffix = data.find('_');  // len8_dlc: "..._9" for a DLC above 8
  if (dlc_suffix != std::string::npos) {
    if (dlc_suffix + 2 != data.size() || hexDigit(data.back()) < 9)
      rejectLine(source, line, "frame '" + field + "' has a bad DLC suffix");
    data.resize(dlc_suffix);
  }
  if (data.size() % 2 != 0 || data.size() > 16 || (!data.empty() && !allHex(data)))
    rejectLine(source, line, "frame '" + field + "' has data that is not 0 to 8 bytes of hex");
  out.kind = CandumpLine::Kind::kClassic;
  out.frame.id = static_cast<std::uint32_t>(std::strtoul(id.c_str(), nullptr, 16));
  if (out.frame.id > 0x7FF) rejectLine(source, line, "frame '" + field + "': a standard id is at most 7FF");
  out.frame.dlc = static_cast<std::uint8_t>(data.size() / 2);
  for (std::size_t k = 0; k < out.frame.dlc; ++k)
    out.frame.data[k] = static_cast<std::uint8_t>(hexDigit(data[2 * k]) * 16 + hexDigit(data[2 * k + 1]));
}

std::vector<std::string> fieldsOf(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream words(line);
  for (std::string w; words >> w;) fields.push_back(w);
  return fields;
}

// The driver's messages and the columns their signals become.
struct MappedMessage {
  const MessageLayout* layout = nullptr;
  std::vector<std::string> columns;
  int last_counter = -1;
  // Decoded frames: time, then one value per signal.
  std::vector<double> times;
  std::vector<std::array<double, MessageLayout::kMaxSignals>> values;
};

std::vector<MappedMessage> mappedMessages(const SignalMap& map) {
  namespace sc = io::standard_columns;
  std::vector<MappedMessage> out;
  auto add = [&](const char* name, std::vector<std::string> columns) {
    const MessageLayout* m = map.find(name);
    if (!m) return;
    if (m->signals.size() != columns.size())
      throw std::invalid_argument("candump: the signal map's " + std::string(name) + " has " +
                                  std::to_string(m->signals.size()) + " signals; plsa reads it as " +
                                  std::to_string(columns.size()));
    out.push_back({m, std::move(columns), -1, {}, {}});
  };
  add("pressure_sensor", sc::pressures());  // first: the rows follow it
  add("valve_command", sc::commands());
  add("tip_angle", sc::tipAngles());
  if (out.empty() || out.front().layout->name != "pressure_sensor")
    throw std::invalid_argument("candump: the signal map has no pressure_sensor message to time the rows by");
  return out;
}

// What was read besides the mapped frames, for warnings.
struct Tally {
  std::size_t lines = 0, unknown = 0, extended = 0, remote = 0, fd = 0;  // lines: frames read
  std::map<std::string, std::size_t> dropped, gaps;                      // by message
  std::set<std::string> interfaces;
};

void decodeLine(const CandumpLine& l, std::vector<MappedMessage>& messages, Tally& tally, const std::string& source,
                std::size_t line) {
  if (l.kind != CandumpLine::Kind::kClassic) {
    ++(l.kind == CandumpLine::Kind::kExtended ? tally.extended
       : l.kind == CandumpLine::Kind::kRemote ? tally.remote
                                              : tally.fd);
    return;
  }
  for (MappedMessage& m : messages) {
    if (m.layout->id != l.frame.id) continue;
    std::array<double, MessageLayout::kMaxSignals> v{};
    const DecodeStatus status = decodeFrame(*m.layout, l.frame, v.data(), m.last_counter);
    if (status == DecodeStatus::kWrongLength || status == DecodeStatus::kBadChecksum) {
      ++tally.dropped[m.layout->name + " (" + toString(status) + ")"];
      return;
    }
    if (status == DecodeStatus::kCounterGap) ++tally.gaps[m.layout->name];
    if (!m.times.empty() && l.time_s < m.times.back())
      rejectLine(source, line,
                 "a " + m.layout->name + " frame older than the one before it (each message in time order)");
    m.times.push_back(l.time_s);
    m.values.push_back(v);
    return;
  }
  ++tally.unknown;
}

// The sensor's period: the median interval of its frames (robust to jitter
// and drop-outs), then the whole span over the cycles it holds (the time
// stamps' microseconds, against an epoch, round each interval by ~0.1 us).
double sensorPeriod(const std::vector<double>& t) {
  std::vector<double> d;
  for (std::size_t k = 1; k < t.size(); ++k) d.push_back(t[k] - t[k - 1]);
  const double interval = median(std::move(d)), span = t.back() - t.front();
  if (!(interval > 0.0)) return interval;
  return span / std::max(1.0, std::round(span / interval));
}

// The uniform grid: one row per bus cycle of the pressure sensor (its median
// frame interval dt), row r at the sensor's time t_r = t_0 + r dt, holding
// each message's latest frame before the cycle ends (t_r + dt / 2), so the
// frames a cycle sends land in one row; from the first cycle in which every
// message present has been seen to the sensor's last frame.
io::Log gridded(std::vector<MappedMessage>& messages, const std::string& source, std::vector<std::string>& warnings) {
  std::vector<MappedMessage*> present;
  for (MappedMessage& m : messages)
    if (!m.times.empty()) present.push_back(&m);
  const std::vector<double>& sensor = messages.front().times;
  if (sensor.size() < 3)
    throw std::runtime_error(source + ": " + std::to_string(sensor.size()) +
                             " pressure_sensor frames; a log needs at least 3 (is the signal map the bus's?)");
  const double dt = sensorPeriod(sensor);
  if (!(dt > 0.0)) {
    const bool one_stamp = sensor.back() == sensor.front();
    throw std::runtime_error(source + (one_stamp ? ": the pressure_sensor frames share one time stamp"
                                                 : ": half or more of the pressure_sensor frames repeat the time "
                                                   "stamp before them (frames logged twice?)"));
  }
  std::size_t first = 0;
  for (const MappedMessage* m : present)
    while (first < sensor.size() && !(m->times.front() < sensor[first] + 0.5 * dt)) ++first;
  const double start = first < sensor.size() ? sensor[first] : sensor.back();
  // Sized from the frames before allocating: a grid mostly of held values
  // (a stamp far off, or hours without the sensor) is refused, not filled.
  const double cycles = std::floor((sensor.back() - start) / dt + 0.5) + 1.0;
  if (first >= sensor.size() || !(cycles >= 2.0))
    throw std::runtime_error(source + ": fewer than 2 rows once every message has been seen");
  if (cycles > 2.0 * static_cast<double>(sensor.size() - first) + 100.0)
    throw std::runtime_error(source + ": the pressure_sensor's " + std::to_string(sensor.size() - first) +
                             " frames span " + std::to_string(cycles) + " of its " + std::to_string(dt) +
                             " s cycles: most rows would be gaps (a time stamp far off, or a long silence; "
                             "split the log)");
  const auto rows = static_cast<Eigen::Index>(cycles);
  io::Log log;
  log.source = source;
  log.columns = {io::standard_columns::kTime};
  for (const MappedMessage* m : present) log.columns.insert(log.columns.end(), m->columns.begin(), m->columns.end());
  log.data.resize(rows, static_cast<Eigen::Index>(log.columns.size()));
  std::vector<std::size_t> at(present.size(), 0);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const double cycle_end = start + (static_cast<double>(r) + 0.5) * dt;
    log.data(r, 0) = static_cast<double>(r) * dt;
    Eigen::Index col = 1;
    for (std::size_t k = 0; k < present.size(); ++k) {
      const MappedMessage& m = *present[k];
      while (at[k] + 1 < m.times.size() && m.times[at[k] + 1] < cycle_end) ++at[k];
      for (std::size_t s = 0; s < m.columns.size(); ++s) log.data(r, col++) = m.values[at[k]][s];
    }
  }
  std::size_t long_gaps = 0;
  double longest = 0.0;
  for (std::size_t k = 1; k < sensor.size(); ++k)
    if (sensor[k] - sensor[k - 1] > 2.5 * dt) ++long_gaps, longest = std::max(longest, sensor[k] - sensor[k - 1]);
  if (long_gaps > 0)
    warnings.push_back(std::to_string(long_gaps) + " gaps in the pressure_sensor frames (longest " +
                       std::to_string(longest) + " s): the rows across them hold the last values");
  log.metadata["sample_time_s"] = std::to_string(dt);
  log.metadata["candump_start_s"] = std::to_string(start);
  return log;
}

void tallyWarnings(const Tally& tally, const std::vector<MappedMessage>& messages, std::vector<std::string>& out) {
  for (const auto& [what, n] : tally.dropped) out.push_back(std::to_string(n) + " " + what + " frames dropped");
  for (const auto& [what, n] : tally.gaps) out.push_back(std::to_string(n) + " counter gaps in " + what);
  if (tally.unknown) out.push_back(std::to_string(tally.unknown) + " frames of ids the signal map does not read");
  if (tally.extended + tally.remote + tally.fd)
    out.push_back(std::to_string(tally.extended) + " extended, " + std::to_string(tally.remote) + " remote and " +
                  std::to_string(tally.fd) + " CAN FD frames skipped");
  if (tally.interfaces.size() > 1) {
    std::string names;
    for (const auto& i : tally.interfaces) names += (names.empty() ? "" : ", ") + i;
    out.push_back("frames from several interfaces (" + names + ") read as one bus");
  }
  for (const MappedMessage& m : messages)
    if (m.times.empty() && m.layout->name != "pressure_sensor")
      out.push_back("no " + m.layout->name + " frames: its columns are absent");
}

}  // namespace

CandumpLine parseCandumpLine(const std::string& line, const std::string& source, std::size_t line_number) {
  const std::vector<std::string> fields = fieldsOf(line);
  // candump -l / -L: "(time) interface frame", optionally a direction flag (R/T) after it.
  if (fields.size() < 3 || fields.size() > 4 || (fields.size() == 4 && fields[3] != "R" && fields[3] != "T"))
    rejectLine(source, line_number, "not a candump log line '(time) interface id#data'");
  CandumpLine out;
  out.time_s = timeStamp(fields[0], source, line_number);
  out.interface = fields[1];
  // A network interface's name: warnings quote it, so escape sequences or a NUL must not pass.
  if (out.interface.size() > 15 || std::any_of(out.interface.begin(), out.interface.end(), [](char c) {
        return static_cast<unsigned char>(c) < 0x21 || static_cast<unsigned char>(c) > 0x7e;
      }))
    rejectLine(source, line_number,
               "the interface name is not 1 to 15 printable ASCII characters (a network "
               "interface's name)");
  frameField(fields[2], out, source, line_number);
  return out;
}

std::string candumpLine(double time_s, const std::string& interface, const CanFrame& frame) {
  char head[48];
  std::snprintf(head, sizeof head, "(%.6f) ", time_s);
  std::string line = head + interface;
  std::snprintf(head, sizeof head, " %03X#", static_cast<unsigned>(frame.id & 0x7FF));
  line += head;
  static const char kHex[] = "0123456789ABCDEF";
  for (int b = 0; b < frame.dlc && b < 8; ++b) {
    line += kHex[frame.data[static_cast<std::size_t>(b)] >> 4];
    line += kHex[frame.data[static_cast<std::size_t>(b)] & 0xF];
  }
  return line + "\n";
}

bool looksLikeCandump(const std::string& head) {
  const std::string first = head.substr(0, head.find('\n'));
  try {
    parseCandumpLine(first, "", 1);
    return true;
  } catch (const std::runtime_error&) {
    return false;
  }
}

io::Log readCandumpLog(std::istream& in, const std::string& source, const SignalMap& map) {
  std::vector<MappedMessage> messages = mappedMessages(map);
  Tally tally;
  std::string line;
  for (std::size_t number = 1;; ++number) {
    line.clear();
    char c = 0;
    bool any = false;
    while (in.get(c) && c != '\n') {
      any = true;
      if (line.size() >= kMaxCandumpLineBytes)
        rejectLine(source, number, "line longer than " + std::to_string(kMaxCandumpLineBytes) + " bytes");
      line.push_back(c);
    }
    if (!any && !in) break;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    if (++tally.lines > kMaxCandumpFrames)
      rejectLine(source, number, "more than " + std::to_string(kMaxCandumpFrames) + " frames; split the log");
    const CandumpLine l = parseCandumpLine(line, source, number);
    if (tally.interfaces.size() < 16) tally.interfaces.insert(l.interface);
    decodeLine(l, messages, tally, source, number);
  }
  if (tally.lines == 0) throw std::runtime_error(source + ": no frames (an empty candump log)");
  std::vector<std::string> warnings;
  io::Log log = gridded(messages, source, warnings);
  tallyWarnings(tally, messages, warnings);
  log.warnings.insert(log.warnings.end(), warnings.begin(), warnings.end());
  log.metadata["candump_frames"] = std::to_string(tally.lines);
  log.metadata["signal_map"] = map.profile;
  return log;
}

namespace {

// A signal whose resolution (|scale| per bit) is coarser than its column's
// whole span would write a varying column as one or two values (a scale of
// -1 bar for commands under 0.5 bar wrote every one as 0): refused. A column
// that moves less than kSteadySpan (bar or deg: 1 mbar, 0.001 deg) is
// steady, and its noise may be lost.
constexpr double kSteadySpan = 1e-3;

void checkResolution(const std::string& path, const io::Log& log, const MessageLayout& m,
                     const std::vector<int>& columns) {
  for (std::size_t s = 0; s < columns.size(); ++s) {
    const auto column = log.data.col(columns[s]);
    const double span = column.maxCoeff() - column.minCoeff(), step = std::abs(m.signals[s].scale);
    if (span > kSteadySpan && step > span) {
      std::ostringstream msg;
      msg.precision(6);
      msg << path << ": " << m.name << "." << m.signals[s].name << " steps by " << step << " (its scale) but "
          << log.columns[static_cast<std::size_t>(columns[s])] << " of " << log.source << " spans only " << span
          << ": every value would be written as one or two levels; use a finer scale in the signal map";
      throw std::invalid_argument(msg.str());
    }
  }
}

// Which value of a row a message's signals cannot carry, named with its
// column and the signal's range (a frame that cannot be encoded).
std::invalid_argument uncarried(const std::string& path, const io::Log& log, Eigen::Index row, const MessageLayout& m,
                                const std::vector<int>& columns) {
  std::ostringstream msg;
  msg.precision(9);
  msg << path << ": row " << row + 1 << " of " << log.source << ": " << m.name;
  for (std::size_t s = 0; s < columns.size(); ++s) {
    const double v = log.data(row, columns[s]);
    const PhysicalRange range = physicalRange(m.signals[s]);
    if (!(v >= range.lo && v <= range.hi)) {
      msg << "." << m.signals[s].name << " cannot carry " << log.columns[static_cast<std::size_t>(columns[s])] << " = "
          << v << " (its range is " << range.lo << " to " << range.hi << ")";
      return std::invalid_argument(msg.str());
    }
  }
  msg << " cannot carry its values (a signal out of its range, or not finite)";
  return std::invalid_argument(msg.str());
}

}  // namespace

void writeCandumpLog(const std::string& path, const io::Log& log, const SignalMap& map) {
  std::vector<MappedMessage> messages = mappedMessages(map);
  std::vector<std::vector<int>> columns;  // per message written: the log's column of each signal
  std::vector<const MappedMessage*> written;
  for (const MappedMessage& m : messages) {
    std::vector<int> cols;
    for (const std::string& name : m.columns)
      if (log.hasColumn(name)) cols.push_back(log.columnIndex(name));
    if (cols.size() == m.columns.size()) {
      written.push_back(&m);
      columns.push_back(cols);
    } else if (m.layout->name == "pressure_sensor") {
      throw std::invalid_argument(path + ": a candump log needs the columns p_1.. of pressure_sensor; " + log.source +
                                  " lacks some");
    }
  }
  for (std::size_t k = 0; k < written.size(); ++k) checkResolution(path, log, *written[k]->layout, columns[k]);
  const int time = log.columnIndex(io::standard_columns::kTime);
  std::string text;
  std::array<std::uint8_t, 3> counter{};
  for (Eigen::Index r = 0; r < log.samples(); ++r)
    for (std::size_t k = 0; k < written.size(); ++k) {
      std::array<double, MessageLayout::kMaxSignals> v{};
      for (std::size_t s = 0; s < columns[k].size(); ++s) v[s] = log.data(r, columns[k][s]);
      CanFrame f;
      const MessageLayout& m = *written[k]->layout;
      if (!encodeFrame(m, v.data(), counter[k]++, f)) throw uncarried(path, log, r, m, columns[k]);
      // candump's (seconds.micros) field: seconds since 1970 at most, never negative (its reader refuses a sign).
      if (!(log.data(r, time) >= 0.0 && log.data(r, time) < 1e11))
        throw std::invalid_argument(path + ": row " + std::to_string(r + 1) + " of " + log.source +
                                    ": time_s is not a time candump writes (0 to 1e11 s)");
      text += candumpLine(log.data(r, time), "can0", f);
    }
  writeTextFile(path, text, "candump log");
}

io::LogFormat candumpLogFormat() {
  io::LogFormat f;
  f.name = "candump";
  f.description = "a candump bus log";
  f.plural = "candump bus logs";
  f.extensions = {".candump"};
  f.sniff = looksLikeCandump;
  f.read = [](std::istream& in, const std::string& source, const io::ReadOptions& options) {
    const SignalMap map = options.can_profile.empty() ? defaultSignalMap() : loadSignalMap(options.can_profile);
    io::Log log = readCandumpLog(in, source, map);
    for (const std::string& column : options.required)
      if (!log.hasColumn(column))
        throw std::runtime_error(source + ": no column '" + column + "' (the signal map '" + map.profile +
                                 "' gives none; its frames decode to the columns of valve_command, "
                                 "pressure_sensor and tip_angle)");
    return log;
  };
  f.write = [](const std::string& path, const io::Log& log, const io::WriteOptions& options) {
    writeCandumpLog(path, log, options.can_profile.empty() ? defaultSignalMap() : loadSignalMap(options.can_profile));
  };
  return f;
}

void registerLogFormats(io::LogReaderRegistry& registry) { registry.add(candumpLogFormat(), io::OnDuplicate::Replace); }

}  // namespace plsa::can
