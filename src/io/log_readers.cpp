#include "plsa/io/log_readers.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "plsa/core/text_file.hpp"

namespace plsa::io {

namespace {

bool endsWith(const std::string& name, const std::string& ending) {
  return !ending.empty() && name.size() > ending.size() &&
         name.compare(name.size() - ending.size(), ending.size(), ending) == 0;
}

std::string fileName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

std::string joined(const std::vector<std::string>& names) {
  if (names.empty()) return "nothing";
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// The first bytes of a stream, which is left at its start again.
std::string headOf(std::istream& in, std::size_t bytes) {
  std::string head(bytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(bytes));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  in.clear();
  in.seekg(0);
  return head;
}

}  // namespace

struct LogReaderRegistry::State {
  mutable std::mutex mutex;
  std::vector<std::shared_ptr<const LogFormat>> formats;

  std::vector<std::shared_ptr<const LogFormat>> snapshot() const {
    std::lock_guard<std::mutex> lock(mutex);
    return formats;
  }
  // How many first bytes recognition needs: the longest magic, or kSniffBytes
  // when some format sniffs.
  std::size_t headBytes() const {
    std::size_t n = 0;
    for (const auto& f : snapshot()) n = std::max(n, f->sniff ? kSniffBytes : f->magic.size());
    return n;
  }
};

LogReaderRegistry::LogReaderRegistry() : state_(std::make_unique<State>()) {}
LogReaderRegistry::~LogReaderRegistry() = default;

bool LogReaderRegistry::add(LogFormat format, OnDuplicate on_duplicate) {
  if (format.name.empty()) throw std::invalid_argument("log formats: a format needs a name");
  std::lock_guard<std::mutex> lock(state_->mutex);
  auto& formats = state_->formats;
  const auto same = std::find_if(formats.begin(), formats.end(), [&](const auto& f) { return f->name == format.name; });
  if (same != formats.end() && on_duplicate == OnDuplicate::Refuse)
    throw std::invalid_argument("log formats: '" + format.name + "' is already registered (as " + (*same)->description +
                                ")");
  if (format.fallback)
    for (const auto& f : formats)
      if (f->fallback && f->name != format.name)
        throw std::invalid_argument("log formats: '" + format.name + "' cannot also read unrecognised files: '" +
                                    f->name + "' does");
  auto shared = std::make_shared<const LogFormat>(std::move(format));
  if (same != formats.end()) {
    *same = std::move(shared);
    return true;
  }
  formats.push_back(std::move(shared));
  return false;
}

std::shared_ptr<const LogFormat> LogReaderRegistry::find(const std::string& name) const {
  for (const auto& f : state_->snapshot())
    if (f->name == name) return f;
  return nullptr;
}

std::vector<std::string> LogReaderRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& f : state_->snapshot()) out.push_back(f->name);
  return out;
}

std::vector<std::string> LogReaderRegistry::readable() const {
  std::vector<std::string> out;
  for (const auto& f : state_->snapshot())
    if (f->read) out.push_back(f->name);
  return out;
}

std::vector<std::string> LogReaderRegistry::writable() const {
  std::vector<std::string> out;
  for (const auto& f : state_->snapshot())
    if (f->write) out.push_back(f->name);
  return out;
}

std::shared_ptr<const LogFormat> LogReaderRegistry::recognise(const std::string& path, const std::string& head) const {
  const auto formats = state_->snapshot();
  for (const auto& f : formats)
    if (!f->magic.empty() && head.compare(0, f->magic.size(), f->magic) == 0) return f;
  for (const auto& f : formats)
    if (f->sniff && f->sniff(head)) return f;
  const std::string name = fileName(path);
  for (const auto& f : formats)
    if (f->magic.empty())
      for (const auto& e : f->extensions)
        if (endsWith(name, e)) return f;
  for (const auto& f : formats)
    if (f->fallback) return f;
  return nullptr;
}

bool LogReaderRegistry::looksLikeLog(const std::string& path) const {
  const auto formats = state_->snapshot();
  const std::string name = fileName(path);
  for (const auto& f : formats)
    for (const auto& e : f->extensions)
      if (endsWith(name, e)) return true;
  const std::size_t n = state_->headBytes();
  if (n == 0) return false;
  std::ifstream in(path, std::ios::binary);
  const std::string head = headOf(in, n);
  for (const auto& f : formats)
    if ((!f->magic.empty() && head.compare(0, f->magic.size(), f->magic) == 0) || (f->sniff && f->sniff(head)))
      return true;
  return false;
}

std::string LogReaderRegistry::logFileKinds() const {
  std::vector<std::string> kinds;
  for (const auto& f : state_->snapshot())
    for (const auto& e : f->extensions) kinds.push_back(e);
  for (const auto& f : state_->snapshot())
    if (!f->magic.empty() || f->sniff) kinds.push_back(f->plural + " by content");
  std::string s;  // "a", "a or b", "a, b, or c"
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    if (i > 0) s += kinds.size() > 2 ? ", " : " ";
    if (i > 0 && i + 1 == kinds.size()) s += "or ";
    s += kinds[i];
  }
  return "(" + s + ")";
}

Log LogReaderRegistry::read(std::istream& in, const std::string& source, const ReadOptions& options) const {
  const auto format = recognise(source, headOf(in, state_->headBytes()));
  if (!format)
    throw std::invalid_argument(source + ": not a log format this build knows; it reads: " + joined(readable()));
  if (!format->read)
    throw std::invalid_argument(source + ": " + format->description + ", which this build cannot read" +
                                (format->missing.empty() ? "" : " (" + format->missing + ")") +
                                "; it reads: " + joined(readable()));
  return format->read(in, source, options);
}

Log LogReaderRegistry::read(const std::string& path, const ReadOptions& options) const {
  refuseNulInPath(path);
  // A pipe can be read once: take it whole (bounded), then look at its first bytes.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    // A device (/dev/zero) would be read up to the pipe limit, a gigabyte, before it was refused.
    if (std::filesystem::exists(path, ec) && !std::filesystem::is_fifo(path, ec))
      throw std::invalid_argument(path + ": not a log file (a folder, a device or a socket)");
    std::istringstream piped(readTextFile(path, "log", kMaxPipedLogBytes));
    return read(piped, path, options);
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(path + ": cannot open for reading");
  return read(file, path, options);
}

void LogReaderRegistry::write(const std::string& path, const Log& log, const WriteOptions& options) const {
  const auto formats = state_->snapshot();
  const std::string name = fileName(path);
  std::shared_ptr<const LogFormat> format;
  for (const auto& f : formats)
    for (const auto& e : f->extensions)
      if (!format && endsWith(name, e)) format = f;
  if (!format)
    for (const auto& f : formats)
      if (f->fallback) format = f;
  if (!format || !format->write)
    throw std::invalid_argument(path + ": " +
                                (format ? format->description + ", which this build cannot write" +
                                              (format->missing.empty() ? "" : " (" + format->missing + ")")
                                        : std::string("not a log format this build knows")) +
                                "; it writes: " + joined(writable()));
  format->write(path, log, options);
}

LogFormat csvLogFormat() {
  LogFormat f;
  f.name = "csv";
  f.description = "a CSV log";
  f.plural = "CSV logs";
  f.extensions = {".csv"};
  f.fallback = true;
  f.read = [](std::istream& in, const std::string& source, const ReadOptions& options) {
    return readCsvLog(in, source, options);
  };
  f.write = [](const std::string& path, const Log& log, const WriteOptions&) { writeCsvLog(path, log); };
  return f;
}

LogFormat lcmLogPlaceholder() {
  LogFormat f;
  f.name = "lcm";
  f.description = "an LCM event log";
  f.plural = "LCM event logs";
  f.extensions = {".lcmlog"};
  f.magic = std::string("\xED\xA1\xDA\x01", 4);  // the sync word every event starts with
  f.missing = "built without LCM";
  return f;
}

LogReaderRegistry& logReaders() {
  static LogReaderRegistry* const registry = [] {
    auto* r = new LogReaderRegistry;  // never destroyed: usable from other statics' destructors
    r->add(csvLogFormat());
    r->add(lcmLogPlaceholder());
    return r;
  }();
  return *registry;
}

Log readLog(const std::string& path, const ReadOptions& options) { return logReaders().read(path, options); }

void writeLog(const std::string& path, const Log& log, const WriteOptions& options) {
  logReaders().write(path, log, options);
}

}  // namespace plsa::io
