#include "plsa/lcm/lcm_log.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "plsa/lcm/state_codec.hpp"

namespace plsa::lcm {
namespace {

const std::vector<std::string> kColumns = {"time_s", "cmd_1", "cmd_2", "cmd_3", "p_1",
                                           "p_2",    "p_3",   "bend_deg", "steer_deg"};

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

io::Log readLcmLog(const std::string& path, const std::string& channel) {
  ::lcm::LogFile file(path, "r");
  if (!file.good()) throw std::runtime_error(path + ": cannot open as an LCM event log");
  std::vector<double> values;
  long other = 0;
  long event_index = 0;
  double last_time = -INFINITY;
  while (const ::lcm::LogEvent* ev = file.readNextEvent()) {
    ++event_index;
    if (ev->channel != channel) {
      ++other;
      continue;
    }
    plsa_lcm::actuator_state_t m;
    if (m.decode(ev->data, 0, ev->datalen) != ev->datalen)
      throw std::runtime_error(path + ": event " + std::to_string(event_index) + " on " + channel +
                               " is not a valid plsa_lcm.actuator_state_t (truncated or wrong type)");
    double row[9];
    try {
      toRow(m, row);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(path + ": event " + std::to_string(event_index) + ": " + e.what());
    }
    for (double v : row)
      if (!std::isfinite(v))
        throw std::runtime_error(path + ": event " + std::to_string(event_index) + " has a NaN or Inf field");
    if (!(row[0] > last_time))
      throw std::runtime_error(path + ": event " + std::to_string(event_index) + ": time " +
                               std::to_string(row[0]) + " s is not after the previous state's");
    last_time = row[0];
    values.insert(values.end(), row, row + 9);
  }
  if (values.empty())
    throw std::runtime_error(path + ": no actuator-state messages on channel " + channel + " (" +
                             std::to_string(event_index) + " events in all)");
  io::Log log;
  log.source = path;
  log.columns = kColumns;
  const auto rows = static_cast<Eigen::Index>(values.size() / 9);
  log.data = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), rows, 9);
  log.metadata["source"] = "LCM event log, channel " + channel;
  log.metadata["events_on_other_channels"] = std::to_string(other);
  return log;
}

void writeLcmLog(const std::string& path, const io::Log& log, const std::string& channel) {
  const Eigen::MatrixXd cols = log.columnsOf(kColumns);
  ::lcm::LogFile file(path, "w");
  if (!file.good()) throw std::runtime_error(path + ": cannot open for writing");
  std::vector<char> buf;
  for (Eigen::Index r = 0; r < cols.rows(); ++r) {
    plsa_lcm::actuator_state_t m;
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
    ::lcm::LogEvent ev;
    ev.eventnum = r;
    ev.timestamp = m.utime;
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(buf.size());
    ev.data = buf.data();
    if (file.writeEvent(&ev) != 0) throw std::runtime_error(path + ": write failed");
  }
}

io::Log readLogFile(const std::string& path, const io::CsvReadOptions& options) {
  if (endsWith(path, ".lcmlog") || endsWith(path, ".lcm")) {
    io::Log log = readLcmLog(path);
    for (const auto& r : options.required)
      if (!log.hasColumn(r)) throw std::runtime_error(path + ": LCM log has no column '" + r + "'");
    return log;
  }
  return io::readCsvLog(path, options);
}

}  // namespace plsa::lcm
