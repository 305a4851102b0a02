#include "plsa/io/csv_log.hpp"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <vector>

#include "plsa/core/median.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/core/printable_text.hpp"
#include "plsa/core/text_file.hpp"

namespace plsa::io {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> splitFields(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) out.push_back(trim(field));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

// Shortest text that reads back to the same double.
std::string shortest(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

[[noreturn]] void fail(const std::string& path, std::size_t line, const std::string& why) {
  throw std::runtime_error(path + ":" + std::to_string(line) + ": " + why);
}

}  // namespace

bool Log::hasColumn(const std::string& name) const {
  return std::find(columns.begin(), columns.end(), name) != columns.end();
}

std::string columnList(const std::vector<std::string>& names, std::size_t max_chars) {
  std::string list;
  for (const auto& n : names) {
    if (!list.empty() && list.size() + n.size() > max_chars)
      return list + ", ... (" + std::to_string(names.size()) + " columns)";
    list += (list.empty() ? "" : ", ") + n;
  }
  return list;
}

int Log::columnIndex(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end())
    throw std::invalid_argument(source + ": no column '" + name + "' (columns: " + columnList(columns) + ")");
  return static_cast<int>(it - columns.begin());
}

Eigen::VectorXd Log::column(const std::string& name) const { return data.col(columnIndex(name)); }

Eigen::MatrixXd Log::columnsOf(const std::vector<std::string>& names) const {
  Eigen::MatrixXd out(data.rows(), static_cast<Eigen::Index>(names.size()));
  for (std::size_t i = 0; i < names.size(); ++i)
    out.col(static_cast<Eigen::Index>(i)) = data.col(columnIndex(names[i]));
  return out;
}

namespace {

// Lines of at most kMaxCsvLineBytes; knows whether the last one ended in '\n'.
class LineReader {
 public:
  LineReader(std::istream& in, const std::string& source) : in_(in), source_(source) {}

  bool next(std::string& line) {
    line.clear();
    std::streambuf* buf = in_.rdbuf();
    using traits = std::char_traits<char>;
    for (auto got = buf ? buf->sbumpc() : traits::eof(); !traits::eq_int_type(got, traits::eof());
         got = buf->sbumpc()) {
      const char c = traits::to_char_type(got);
      if (c == '\n') {
        ++number_;
        return true;
      }
      if (c == '\0') fail(source_, number_ + 1, "NUL byte: binary data, not a CSV log");
      if (line.size() >= kMaxCsvLineBytes)
        fail(source_, number_ + 1,
             "line longer than " + std::to_string(kMaxCsvLineBytes >> 20) + " MiB: not a CSV log");
      line.push_back(c);
    }
    if (line.empty()) return false;
    ++number_;
    unterminated_ = true;
    return true;
  }
  std::size_t number() const { return number_; }
  bool lastLineUnterminated() const { return unterminated_; }

 private:
  std::istream& in_;
  const std::string& source_;
  std::size_t number_ = 0;
  bool unterminated_ = false;
};

// A '#' line: "# key: value" (no blank before the colon) is metadata, any
// other a comment.
// Up to kKeptCommentLines of each are kept (a key already kept takes a
// later value); the rest are counted (`dropped`), so a file of millions of
// '#' lines costs no memory beyond them.
void readCommentLine(const std::string& t, Log& log, std::size_t& dropped) {
  const std::string body = trim(t.substr(1));
  const auto colon = body.find(':');
  if (colon != std::string::npos && colon > 0 && body.find_first_of(" \t") > colon) {
    const std::string key = trim(body.substr(0, colon));
    if (log.metadata.size() < kKeptCommentLines || log.metadata.count(key) > 0)
      log.metadata[key] = trim(body.substr(colon + 1));
    else
      ++dropped;
  } else if (log.comments.size() < kKeptCommentLines) {
    log.comments.push_back(body);
  } else {
    ++dropped;
  }
}

// The header: every column named once, the required ones present; returns
// the time column's index, or -1 when none is checked.
int readHeader(std::vector<std::string> fields, const std::string& path, std::size_t lineno,
               const CsvReadOptions& options, Log& log) {
  for (auto& f : fields)  // "name", as spreadsheets and pandas quote it
    if (f.size() >= 2 && f.front() == '"' && f.back() == '"') f = trim(f.substr(1, f.size() - 2));
  std::unordered_set<std::string> seen;  // linear in the columns: a header of 10^5 names reads in milliseconds
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (fields[i].empty()) fail(path, lineno, "header column " + std::to_string(i + 1) + " has no name");
    if (const std::size_t at = controlCharacterAt(fields[i]); at != std::string::npos)
      fail(path, lineno,  // it would be written into models and garble every message naming it
           "header column " + std::to_string(i + 1) + " has the control character " +
               controlCharacterName(fields[i][at]) + " at byte " + std::to_string(at) +
               " of its name (column names are printable text)");
    if (const std::size_t at = utf8ProblemAt(fields[i]); at != std::string::npos)
      fail(path, lineno,  // written into a model's JSON, it would fail there after the whole identification
           "header column " + std::to_string(i + 1) + " is not UTF-8 text at byte " + std::to_string(at) +
               " of its name (a C1 control or a byte outside UTF-8; column names are printable text)");
    if (!seen.insert(fields[i]).second) fail(path, lineno, "header names column '" + fields[i] + "' twice");
  }
  log.columns = fields;
  for (const auto& r : options.required)
    if (!log.hasColumn(r)) fail(path, lineno, "header has no column '" + r + "' (it has: " + columnList(fields) + ")");
  if (!options.time_column.empty() && log.hasColumn(options.time_column)) return log.columnIndex(options.time_column);
  return -1;
}

// A cell as a message quotes it: at most 48 bytes of it (a 1 MiB cell is not echoed whole).
std::string quotedCell(const std::string& f) {
  if (f.size() <= 48) return "'" + f + "'";
  return "'" + f.substr(0, 40) + "...' (" + std::to_string(f.size()) + " bytes)";
}

// The intervals between consecutive entries of a time column (at least two entries).
std::vector<double> sampleIntervals(const Eigen::Ref<const Eigen::VectorXd>& t) {
  std::vector<double> dt(static_cast<std::size_t>(t.size() - 1));
  for (Eigen::Index k = 1; k < t.size(); ++k) dt[static_cast<std::size_t>(k - 1)] = t(k) - t(k - 1);
  return dt;
}

// A `# sample_rate_hz:` line that the time column contradicts is warned of:
// the time column is what every tool reads (a log declaring 100 Hz and
// stamped at 80 Hz was read at 80 Hz without a word).
void warnOfDeclaredRate(Log& log, int time_col) {
  const auto declared = log.metadata.find("sample_rate_hz");
  if (declared == log.metadata.end() || log.data.rows() < 3) return;
  const ParsedDecimal hz = parseDecimal(declared->second);
  if (hz.kind != DecimalText::kNumber || !(hz.value > 0.0)) return;
  const double measured = 1.0 / median(sampleIntervals(log.data.col(time_col)));
  if (std::abs(measured - hz.value) > 0.01 * measured)
    log.warnings.push_back(log.source + ": its '# sample_rate_hz: " + declared->second +
                           "' disagrees with its time column, which steps at " + significantDigits(measured, 6) +
                           " Hz (the time column is what plsa reads)");
}

// A data row: as many finite numbers as the header has columns, appended to `values`.
void readRow(const std::vector<std::string>& fields, const std::string& path, std::size_t lineno, const Log& log,
             std::vector<double>& values) {
  if (fields.size() != log.columns.size())
    fail(path, lineno,
         "row has " + std::to_string(fields.size()) + " fields, header has " + std::to_string(log.columns.size()));
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const std::string& f = fields[i];
    const ParsedDecimal n = parseDecimal(f);
    if (n.kind == DecimalText::kNotANumber)
      fail(path, lineno, "column '" + log.columns[i] + "': " + quotedCell(f) + " is not a number");
    if (n.kind == DecimalText::kNotDecimal)  // a hex-coded column would be misread
      fail(path, lineno, "column '" + log.columns[i] + "': " + quotedCell(f) + " is not a decimal number");
    if (n.kind == DecimalText::kNotFinite)
      fail(path, lineno, "column '" + log.columns[i] + "': value " + quotedCell(f) + " is not finite");
    values.push_back(n.value);
  }
}

}  // namespace

Log readCsvLog(const std::string& path, const CsvReadOptions& options) {
  refuseNulInPath(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open for reading");
  return readCsvLog(in, path, options);
}

Log readCsvLog(std::istream& in, const std::string& path, const CsvReadOptions& options) {
  Log log;
  log.source = path;
  std::vector<double> values;
  std::string line;
  LineReader lines(in, path);
  bool have_header = false;
  int time_col = -1;
  double last_time = -std::numeric_limits<double>::infinity();
  Eigen::Index rows = 0;
  std::size_t dropped_comments = 0;
  while (lines.next(line)) {
    const std::size_t lineno = lines.number();
    // A UTF-8 byte-order mark (spreadsheets write one) would hide the first column's name.
    if (lineno == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
    const std::string t = trim(line);
    if (t.empty()) continue;
    if (t.find('\r') != std::string::npos)
      fail(path, lineno, "a carriage return inside the line: lines end in CR alone (convert them to LF or CR LF)");
    if (t[0] == '#') {
      readCommentLine(t, log, dropped_comments);
      continue;
    }
    const std::vector<std::string> fields = splitFields(t);
    if (!have_header) {
      time_col = readHeader(fields, path, lineno, options, log);
      have_header = true;
      continue;
    }
    readRow(fields, path, lineno, log, values);
    if (time_col >= 0) {
      const double tt = values[values.size() - fields.size() + static_cast<std::size_t>(time_col)];
      if (!(tt > last_time))
        fail(path, lineno,
             "time " + shortest(tt) + " is not after the previous sample's " + shortest(last_time) +
                 " (time must increase strictly)");
      last_time = tt;
    }
    ++rows;
  }
  if (!have_header) fail(path, lines.number(), "no header line (expected comma-separated column names)");
  if (rows == 0) fail(path, lines.number(), "no data rows after the header");
  if (lines.lastLineUnterminated())
    log.warnings.push_back(path + ":" + std::to_string(lines.number()) +
                           ": the file ends without a newline; its last row may have been cut short (check its "
                           "last value)");
  if (dropped_comments > 0)
    log.warnings.push_back(path + ": " + std::to_string(dropped_comments) + " '#' lines past the first " +
                           std::to_string(kKeptCommentLines) + " comments and metadata keys not kept");
  const auto cols = static_cast<Eigen::Index>(log.columns.size());
  log.data = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(values.data(),
                                                                                                      rows, cols);
  if (time_col >= 0) warnOfDeclaredRate(log, time_col);
  return log;
}

void writeCsvLog(const std::string& path, const Log& log) {
  if (static_cast<Eigen::Index>(log.columns.size()) != log.data.cols())
    throw std::invalid_argument("writeCsvLog: " + std::to_string(log.columns.size()) + " column names for " +
                                std::to_string(log.data.cols()) + " columns");
  // Written a megabyte at a time: a 10-million-row log is not held twice as text.
  writeFileAtomicallyFrom(path, "log", [&](const auto& emit) {
    std::string text;
    for (const auto& [k, v] : log.metadata) text += "# " + k + ": " + v + '\n';
    for (const auto& c : log.comments) text += "# " + c + '\n';
    for (std::size_t i = 0; i < log.columns.size(); ++i) text += (i ? "," : "") + log.columns[i];
    text += '\n';
    for (Eigen::Index r = 0; r < log.data.rows(); ++r) {
      for (Eigen::Index c = 0; c < log.data.cols(); ++c) (text += (c ? "," : "")) += shortest(log.data(r, c));
      text += '\n';
      if (text.size() >= (std::size_t{1} << 20)) {
        emit(text);
        text.clear();
      }
    }
    emit(text);
  });
}

namespace {

// A dropped sample or two is a logger's hiccup; more than 1% of the
// intervals over 1.5 sample times is a log with samples dropped throughout
// or recorded at a second rate, whose k-step horizons would mean other times.
void refuseDroppedSamples(const Log& log, const std::vector<double>& dt, double median) {
  std::size_t long_ones = 0, first = 0;
  for (std::size_t k = 0; k < dt.size(); ++k)
    if (dt[k] > 1.5 * median && long_ones++ == 0) first = k;
  if (long_ones <= 2 || long_ones * 100 <= dt.size()) return;
  std::ostringstream msg;
  msg << log.source << ": " << long_ones << " of " << dt.size() << " sample intervals (the first before data row "
      << first + 2 << ") are over 1.5 times the median sample time " << median
      << " s: samples dropped throughout or a second rate; resample the log to one rate";
  throw std::runtime_error(msg.str());
}

}  // namespace

double checkedSampleTime(const Log& log, const std::string& time_column, double max_gap_factor) {
  const Eigen::VectorXd t = log.column(time_column);
  if (t.size() < 2) throw std::invalid_argument(log.source + ": need two samples to find the sample time");
  const std::vector<double> dt = sampleIntervals(t);
  const double sample_time = median(dt);
  if (!(sample_time >= kMinSampleTimeS && sample_time <= kMaxSampleTimeS)) {
    std::ostringstream msg;
    msg << log.source << ": median sample time " << sample_time << " s of column '" << time_column << "' is outside "
        << kMinSampleTimeS << " to " << kMaxSampleTimeS << " s (is the time column in seconds?)";
    throw std::runtime_error(msg.str());
  }
  refuseDroppedSamples(log, dt, sample_time);
  for (std::size_t k = 0; k < dt.size(); ++k) {
    if (dt[k] > max_gap_factor * sample_time) {
      std::ostringstream msg;
      msg << log.source << ": time gap of " << dt[k] << " s before data row " << k + 2 << " (median sample time "
          << sample_time << " s); split the log at the gap";
      throw std::runtime_error(msg.str());
    }
  }
  return sample_time;
}

}  // namespace plsa::io
