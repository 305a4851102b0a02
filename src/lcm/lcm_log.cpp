#include "plsa/lcm/lcm_log.hpp"

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "plsa/core/text_file.hpp"
#include "plsa/lcm/message_codec.hpp"
#include "plsa/lcm/state_codec.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::lcm {
namespace {

const std::vector<std::string> kColumns = io::standard_columns::recorded();

std::uint64_t bigEndian(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

void putBigEndian(std::string& out, std::uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

// One pass over the events; the caller turns the state messages into rows.
class EventReader {
 public:
  EventReader(std::istream& in, std::string source, std::string channel)
      : in_(in), source_(std::move(source)), channel_(std::move(channel)) {}

  io::Log read() {
    std::vector<double> values;
    while (nextEvent()) {
      if (!on_channel_) continue;
      double row[9];
      toRowChecked(row);
      values.insert(values.end(), row, row + 9);
    }
    if (values.empty())
      throw std::runtime_error(source_ + ": no actuator-state messages on channel " + channel_ + " (" +
                               std::to_string(events_) + " events in all)");
    io::Log log;
    log.source = source_;
    log.columns = kColumns;
    const auto rows = static_cast<Eigen::Index>(values.size() / 9);
    log.data = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(values.data(),
                                                                                                        rows, 9);
    log.metadata["source"] = "LCM event log, channel " + channel_;
    log.metadata["events_on_other_channels"] = std::to_string(other_);
    if (!cut_.empty()) log.warnings.push_back(cut_);
    return log;
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(source_ + ": event " + std::to_string(events_) + " (byte " + std::to_string(start_) +
                             "): " + why);
  }

  // Reads `n` bytes into `buf`; false (and a note) when the file ends first.
  bool take(char* buf, std::size_t n) {
    in_.read(buf, static_cast<std::streamsize>(n));
    offset_ += static_cast<std::uint64_t>(in_.gcount());
    return static_cast<std::size_t>(in_.gcount()) == n || cutShort();
  }

  // The file ended inside the current event: keep what came before, and say so.
  bool cutShort() {
    cut_ = "the log ends inside event " + std::to_string(events_) + " (byte " + std::to_string(start_) +
           "), as a recording stopped mid-write does; the " + std::to_string(events_ - 1) +
           " events before it are read";
    return false;
  }

  bool skip(std::uint64_t n) {
    while (n > 0) {
      const auto step = static_cast<std::streamsize>(std::min<std::uint64_t>(n, 1 << 20));
      in_.ignore(step);
      offset_ += static_cast<std::uint64_t>(in_.gcount());
      if (in_.gcount() != step) return cutShort();
      n -= static_cast<std::uint64_t>(step);
    }
    return true;
  }

  // The next event's header and, on our channel, its data; false at the end.
  bool nextEvent() {
    start_ = offset_;
    std::array<unsigned char, 28> head{};
    in_.read(reinterpret_cast<char*>(head.data()), 4);
    offset_ += static_cast<std::uint64_t>(in_.gcount());
    if (in_.gcount() == 0) return false;
    ++events_;
    if (in_.gcount() < 4) return cutShort();
    if (bigEndian(head.data(), 4) != kLcmLogSyncWord)
      fail(events_ == 1 ? "no LCM sync word: not an LCM event log" : "no LCM sync word: the log is corrupt here");
    if (!take(reinterpret_cast<char*>(head.data()) + 4, 24)) return false;
    const auto channel_len = static_cast<std::int32_t>(bigEndian(head.data() + 20, 4));
    const auto data_len = static_cast<std::int32_t>(bigEndian(head.data() + 24, 4));
    if (channel_len < 1 || channel_len > kMaxChannelBytes)
      fail("channel name length " + std::to_string(channel_len) + " is outside 1.." + std::to_string(kMaxChannelBytes));
    if (data_len < 0) fail("data length " + std::to_string(data_len) + " is negative");
    char name[kMaxChannelBytes];
    if (!take(name, static_cast<std::size_t>(channel_len))) return false;
    on_channel_ = channel_.compare(0, std::string::npos, name, static_cast<std::size_t>(channel_len)) == 0;
    if (!on_channel_) {
      ++other_;
      return skip(static_cast<std::uint64_t>(data_len));
    }
    if (static_cast<std::size_t>(data_len) > kMaxMessageBytes)
      fail("data length " + std::to_string(data_len) + " is above the " + std::to_string(kMaxMessageBytes >> 20) +
           " MiB a message may have");
    data_.resize(static_cast<std::size_t>(data_len));
    return take(data_.data(), data_.size());
  }

  void toRowChecked(double row[9]) {
    const std::string why = decodeMessage(data_.data(), data_.size(), message_);
    if (!why.empty()) fail("on " + channel_ + ": " + why);
    try {
      toRow(message_, row);
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
    for (int i = 0; i < 9; ++i)
      if (!std::isfinite(row[i])) fail("field '" + kColumns[static_cast<std::size_t>(i)] + "' is NaN or Inf");
    if (!(row[0] > last_time_))
      fail("time " + std::to_string(row[0]) + " s is not after the previous state's " + std::to_string(last_time_));
    last_time_ = row[0];
  }

  std::istream& in_;
  std::string source_, channel_;
  std::vector<char> data_;
  plsa_lcm::actuator_state_t message_;
  std::uint64_t offset_ = 0, start_ = 0;
  long events_ = 0, other_ = 0;
  bool on_channel_ = false;
  double last_time_ = -INFINITY;
  std::string cut_;
};

}  // namespace

io::Log readLcmLog(std::istream& in, const std::string& source, const std::string& channel) {
  return EventReader(in, source, channel).read();
}

io::Log readLcmLog(const std::string& path, const std::string& channel) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open as an LCM event log");
  return readLcmLog(in, path, channel);
}

void writeLcmLog(const std::string& path, const io::Log& log, const std::string& channel) {
  if (channel.empty() || channel.size() > static_cast<std::size_t>(kMaxChannelBytes))
    throw std::invalid_argument("writeLcmLog: channel name must have 1 to " + std::to_string(kMaxChannelBytes) +
                                " bytes");
  const Eigen::MatrixXd cols = log.columnsOf(kColumns);
  std::string bytes;
  std::vector<char> buf;
  for (Eigen::Index r = 0; r < cols.rows(); ++r) {
    plsa_lcm::actuator_state_t m;
    // utime is int64 microseconds, read back only up to kMaxLogUtime.
    if (!(std::abs(cols(r, 0)) * 1e6 <= static_cast<double>(kMaxLogUtime)))
      throw std::invalid_argument(path + ": row " + std::to_string(r + 1) + " of " + log.source + ": time_s " +
                                  std::to_string(cols(r, 0)) +
                                  " s is beyond what an LCM event log holds (|time_s| <= 2^53 us, 285 years)");
    m.utime = static_cast<std::int64_t>(std::llround(cols(r, 0) * 1e6));
    m.seq = r;
    m.n_chambers = 3;
    m.command_bar = {cols(r, 1), cols(r, 2), cols(r, 3)};
    m.pressure_bar = {cols(r, 4), cols(r, 5), cols(r, 6)};
    m.bend_deg = cols(r, 7);
    m.steer_deg = cols(r, 8);
    for (auto& row : m.sensor_rotation)
      for (double& v : row) v = 0.0;
    m.vented = 0;
    buf.resize(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    putBigEndian(bytes, kLcmLogSyncWord, 4);
    putBigEndian(bytes, static_cast<std::uint64_t>(r), 8);
    putBigEndian(bytes, static_cast<std::uint64_t>(m.utime), 8);
    putBigEndian(bytes, channel.size(), 4);
    putBigEndian(bytes, buf.size(), 4);
    bytes += channel;
    bytes.append(buf.data(), buf.size());
  }
  writeFileAtomically(path, bytes, "LCM event log");
}

bool isLcmLog(std::istream& in) {
  unsigned char head[4] = {};
  return in.read(reinterpret_cast<char*>(head), 4) && bigEndian(head, 4) == kLcmLogSyncWord;
}

bool isLcmLog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return isLcmLog(in);
}

io::LogFormat lcmLogFormat() {
  io::LogFormat f = io::lcmLogPlaceholder();
  f.missing.clear();
  f.magic.clear();
  putBigEndian(f.magic, kLcmLogSyncWord, 4);
  f.read = [](std::istream& in, const std::string& source, const io::ReadOptions& options) {
    io::Log log = readLcmLog(in, source, options.lcm_channel);
    for (const auto& r : options.required)
      if (!log.hasColumn(r)) throw std::runtime_error(source + ": LCM log has no column '" + r + "'");
    return log;
  };
  f.write = [](const std::string& path, const io::Log& log, const io::WriteOptions& options) {
    writeLcmLog(path, log, options.lcm_channel);
  };
  return f;
}

void registerLogFormats(io::LogReaderRegistry& registry) { registry.add(lcmLogFormat(), io::OnDuplicate::Replace); }

io::Log readLogFile(const std::string& path, const io::CsvReadOptions& options) {
  static const io::LogReaderRegistry* const formats = [] {
    auto* r = new io::LogReaderRegistry;  // never destroyed, as io::logReaders()
    r->add(io::csvLogFormat());
    r->add(lcmLogFormat());
    return r;
  }();
  return formats->read(path, options);
}

}  // namespace plsa::lcm
