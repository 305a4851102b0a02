// Log formats by name: how a file is recognised, read and (optionally)
// written. Tools read every log through a registry, so a build reads what its
// libraries registered and says plainly what it cannot read.
//
// plsa_io registers CSV, and knows an LCM event log by its first bytes
// without being able to read one; the LCM codec (plsa::lcm::registerLogFormats)
// replaces that entry with its reader and writer. Registration is explicit:
// a static initialiser in a static library is dropped by the linker unless
// something else in its object file is used.
#pragma once

#include <cstddef>
#include <functional>
#include <istream>
#include <memory>
#include <string>
#include <vector>

#include "plsa/io/csv_log.hpp"

namespace plsa::io {

/// Options of every reader (the CSV checks; the LCM channel).
using ReadOptions = CsvReadOptions;

struct WriteOptions {
  /// LCM event logs: the channel the actuator-state messages go on.
  std::string lcm_channel = "PLSA_STATE";
  /// candump bus logs: the signal map JSON that encodes the frames ("" for
  /// plsa's default profile).
  std::string can_profile;
};

/// The first bytes of a file LogFormat::sniff looks at.
inline constexpr std::size_t kSniffBytes = 256;

/// Most bytes read from a log that is not a regular file (a pipe is read
/// whole, then recognised by its first bytes).
inline constexpr std::size_t kMaxPipedLogBytes = std::size_t{1} << 30;

struct LogFormat {
  using Reader = std::function<Log(std::istream& in, const std::string& source, const ReadOptions& options)>;
  using Writer = std::function<void(const std::string& path, const Log& log, const WriteOptions& options)>;

  std::string name;         ///< short and unique: "csv", "lcm"
  std::string description;  ///< for messages, with its article: "an LCM event log"
  std::string plural;       ///< "LCM event logs"
  /// File name endings it is known by (".csv"); the name must be longer than
  /// the ending (".csv" alone is no CSV file's name).
  std::vector<std::string> extensions;
  /// The first bytes of every such file ("" for none). A format with magic
  /// bytes is recognised by its content alone, whatever the file's name; its
  /// extensions still pick its files out of a folder and choose the writer.
  std::string magic;
  /// For a text format without magic bytes: whether a file's first
  /// kSniffBytes bytes have its shape (empty: none). Tried after every
  /// format's magic bytes and before the extensions.
  std::function<bool(const std::string& head)> sniff;
  /// Reads whatever no other format claims (one format at most: CSV).
  bool fallback = false;
  /// Empty when this build cannot read the format: then it is only recognised.
  Reader read;
  /// Empty when this build cannot write it.
  Writer write;
  /// Why an unreadable format is unreadable, for messages: "built without LCM".
  std::string missing;
};

/// What a second registration under a taken name does.
enum class OnDuplicate {
  Refuse,   ///< throw std::invalid_argument naming the format
  Replace,  ///< the new format takes the old one's place (and its rank)
};

class LogReaderRegistry {
 public:
  LogReaderRegistry();
  ~LogReaderRegistry();
  LogReaderRegistry(const LogReaderRegistry&) = delete;
  LogReaderRegistry& operator=(const LogReaderRegistry&) = delete;

  /// Adds a format, after those already there (recognition goes in
  /// registration order). Throws std::invalid_argument on an empty name, a
  /// second fallback, or (with OnDuplicate::Refuse) a name already taken.
  /// Returns true when it replaced a format of the same name.
  bool add(LogFormat format, OnDuplicate on_duplicate = OnDuplicate::Refuse);

  /// The format called `name`, or null. Formats are shared and immutable: one
  /// replaced or added later leaves those already handed out as they were.
  std::shared_ptr<const LogFormat> find(const std::string& name) const;
  /// Names in registration order: all, or only those this build reads / writes.
  std::vector<std::string> names() const;
  std::vector<std::string> readable() const;
  std::vector<std::string> writable() const;

  /// The format of a file whose name is `path` and which starts with `head`:
  /// the first whose magic bytes start `head`, else the first whose sniff
  /// takes `head`, else the first without magic bytes whose extension `path`
  /// ends with, else the fallback; null if none.
  std::shared_ptr<const LogFormat> recognise(const std::string& path, const std::string& head) const;
  /// Whether a folder's file is a log: its extension is a format's, or its
  /// first bytes are a format's magic bytes or sniffed as one (so read only
  /// when needed).
  bool looksLikeLog(const std::string& path) const;
  /// "(.csv, .lcmlog, or LCM event logs by content)": what looksLikeLog takes.
  std::string logFileKinds() const;

  /// Reads a file (a pipe whole, up to kMaxPipedLogBytes) with the reader of
  /// its format. Throws std::runtime_error "PATH: cannot open for reading",
  /// and std::invalid_argument for a format this build cannot read, naming
  /// the file, the format, why, and the formats it does read.
  Log read(const std::string& path, const ReadOptions& options = {}) const;
  /// The same from a stream; `source` names it and chooses by extension.
  Log read(std::istream& in, const std::string& source, const ReadOptions& options = {}) const;
  /// Writes with the writer of the format `path`'s extension names, else
  /// with the fallback's. Throws std::invalid_argument naming the file and
  /// the formats this build writes when that format has no writer here.
  void write(const std::string& path, const Log& log, const WriteOptions& options = {}) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// CSV, readable and writable (io::readCsvLog, io::writeCsvLog).
LogFormat csvLogFormat();
/// An LCM event log known by its sync word and .lcmlog, neither readable nor
/// writable: the entry of a build without the LCM codec.
LogFormat lcmLogPlaceholder();

/// The registry the tools use: CSV and the LCM placeholder to begin with.
LogReaderRegistry& logReaders();

/// logReaders().read(path, options).
Log readLog(const std::string& path, const ReadOptions& options = {});
/// logReaders().write(path, log, options).
void writeLog(const std::string& path, const Log& log, const WriteOptions& options = {});

}  // namespace plsa::io
