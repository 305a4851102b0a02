// Time-series logs as CSV: `#` comment lines (metadata as `# key: value`), one
// header line of column names, then numeric rows. The reader rejects malformed
// files with the file, line and reason; nothing is silently skipped or filled.
#pragma once

#include <cmath>
#include <istream>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/io/standard_columns.hpp"

namespace plsa::io {

/// A log in memory: one row per sample, one column per named signal.
struct Log {
  std::string source;                           ///< file it came from (for messages)
  std::vector<std::string> columns;             ///< column names, in file order
  Eigen::MatrixXd data;                         ///< samples x columns
  std::map<std::string, std::string> metadata;  ///< from `# key: value` lines
  std::vector<std::string> comments;            ///< other `#` lines, without the '#'
  /// What the reader accepted but a user should hear of (a last line without
  /// its newline, a recording cut short); tools print these.
  std::vector<std::string> warnings;

  Eigen::Index samples() const { return data.rows(); }
  bool hasColumn(const std::string& name) const;
  /// Index of a column; throws std::invalid_argument naming the file and the
  /// columns it does have.
  int columnIndex(const std::string& name) const;
  Eigen::VectorXd column(const std::string& name) const;
  /// The named columns side by side, in the order given.
  Eigen::MatrixXd columnsOf(const std::vector<std::string>& names) const;
};

/// Column names joined by ", " for a message, cut after about `max_chars`
/// characters with the count of all ("a, b, ... (200001 columns)").
std::string columnList(const std::vector<std::string>& names, std::size_t max_chars = 300);

struct CsvReadOptions {
  /// Strictly increasing time is required when this column exists ("" to skip).
  std::string time_column = standard_columns::kTime;
  /// Columns that must be present.
  std::vector<std::string> required;
  /// When the file is an LCM event log (lcm::readLogFile): the channel whose
  /// actuator-state messages are read.
  std::string lcm_channel = "PLSA_STATE";
  /// When the file is a candump bus log (can::readCandumpLog): the signal map
  /// (JSON or DBC) that decodes its frames ("" for plsa's default profile).
  std::string can_profile;
};

/// Longest line the reader takes: a log's rows are a few hundred bytes, and a
/// file without line breaks (binary data, a wrong path) must not fill memory.
inline constexpr std::size_t kMaxCsvLineBytes = std::size_t{1} << 20;
/// Comment lines, and metadata keys, a log keeps; further ones are counted in a warning.
inline constexpr std::size_t kKeptCommentLines = 1000;

/// Reads a log; throws std::runtime_error "FILE:LINE: reason" on any defect
/// (missing file, no header, duplicate or missing column, ragged row, text or
/// NaN/Inf in a number field, time not strictly increasing, no data rows, a
/// NUL byte, a line above kMaxCsvLineBytes). A UTF-8 byte-order mark is
/// skipped. A last line without its newline is read and warned of (it may
/// have been cut inside its last field).
Log readCsvLog(const std::string& path, const CsvReadOptions& options = {});
/// The same from a stream; `source` names it in messages.
Log readCsvLog(std::istream& in, const std::string& source, const CsvReadOptions& options = {});

/// Writes metadata as `# key: value`, the header and rows at full precision,
/// atomically (a temporary file renamed over `path`).
void writeCsvLog(const std::string& path, const Log& log);

/// Sample times the tools take (100 kHz to one sample a minute).
inline constexpr double kMinSampleTimeS = 1e-5;
inline constexpr double kMaxSampleTimeS = 60.0;

/// Median sample time of the time column; throws if it lies outside
/// [kMinSampleTimeS, kMaxSampleTimeS], if more than 1% of the intervals (and
/// more than two) exceed 1.5 times it (samples dropped throughout, a second
/// rate), or if any step is more than `max_gap_factor` times the median,
/// naming the row and the gap.
double checkedSampleTime(const Log& log, const std::string& time_column = standard_columns::kTime,
                         double max_gap_factor = 1.5);

/// The gap identification and validation tolerate, in sample times: a
/// dropped sample or two, as the real arm's logs have.
inline constexpr double kToleratedGapFactor = 2.5;

/// Whether a log's sample time matches a reference one: within 2%, a clock's
/// error, not another rate.
inline bool sameSampleTime(double sample_time_s, double reference_s) {
  return std::abs(sample_time_s - reference_s) <= 0.02 * reference_s;
}

}  // namespace plsa::io
