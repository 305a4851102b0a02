#include "log_paths.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "plsa/core/text_file.hpp"
#include "plsa/io/log_readers.hpp"

namespace fs = std::filesystem;

namespace plsa::app {

namespace {

// Files of a log folder that are not logs are said, not passed over in silence
// (a trial saved as .txt would otherwise just be missing from the results).
void noteLeftOut(std::vector<std::string> names, const std::string& folder, const std::string& tool) {
  if (names.empty()) return;
  std::sort(names.begin(), names.end());
  std::fprintf(stderr, "%s: note: %s: %zu file%s not read, not being logs %s: %s\n", tool.c_str(), folder.c_str(),
               names.size(), names.size() == 1 ? "" : "s", io::logReaders().logFileKinds().c_str(),
               io::columnList(names).c_str());
}

}  // namespace

std::vector<std::string> logPaths(const std::vector<std::string>& paths, const std::string& tool, bool folders) {
  std::vector<std::string> files;
  for (const auto& p : paths) {
    if (folders && fs::is_directory(p)) {
      std::vector<std::string> in, left_out;
      for (const auto& e : fs::directory_iterator(p))
        if (e.is_regular_file())
          (io::logReaders().looksLikeLog(e.path().string()) ? in : left_out).push_back(e.path().filename().string());
      if (in.empty())
        throw std::invalid_argument(tool + ": " + p + ": no logs in this folder " + io::logReaders().logFileKinds());
      noteLeftOut(left_out, p, tool);
      std::sort(in.begin(), in.end());
      for (std::string& name : in) name = (fs::path(p) / name).string();
      files.insert(files.end(), in.begin(), in.end());
    } else if (fs::is_regular_file(p) || fs::is_fifo(p)) {
      files.push_back(p);
    } else {
      throw std::invalid_argument(tool + ": " + p + (fs::exists(p) ? ": not a log file" : ": no such file") +
                                  (folders ? " or folder" : ""));
    }
  }
  std::map<fs::path, std::string> seen;
  for (const auto& f : files) {
    std::error_code ec;  // a pipe (/dev/stdin, <(...)) has no canonical path: itself
    fs::path canonical = fs::weakly_canonical(f, ec);
    if (ec) canonical = fs::absolute(f);
    const auto [at, fresh] = seen.emplace(canonical, f);
    if (!fresh)
      throw std::invalid_argument(tool + ": " + f + " is given twice" +
                                  (at->second == f ? std::string() : " (also as " + at->second + ")") +
                                  "; each log may appear once");
  }
  return files;
}

}  // namespace plsa::app

#include <cstdio>
#include <system_error>

namespace plsa::app {

namespace {

bool sameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
}

}  // namespace

void refuseOverwritingInputs(const std::string& output, const std::string& option,
                             const std::vector<std::string>& inputs, const std::string& tool) {
  if (output.empty()) return;
  for (const auto& in : inputs)
    if (!in.empty() && sameFile(output, in))
      throw std::invalid_argument(tool + ": " + option + " " + output + " is " +
                                  (in == output ? std::string("an input") : "the input " + in) +
                                  "; plsa never writes over what it reads (choose another output path)");
}

void checkOutputPath(const std::string& output, const std::string& option, const std::vector<std::string>& inputs,
                     const std::string& tool) {
  refuseOverwritingInputs(output, option, inputs, tool);
  refuseMissingOutputFolder(output, option, tool);
}

namespace {

bool mentionsWord(const std::string& text, const std::string& word) {
  const auto boundary = [](char c) { return !std::isalnum(static_cast<unsigned char>(c)) && c != '_'; };
  for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1))
    if ((at == 0 || boundary(text[at - 1])) && (at + word.size() == text.size() || boundary(text[at + word.size()])))
      return true;
  return false;
}

}  // namespace

void warnOfDeclaredUnits(const io::Log& log, const std::string& input_unit, const std::string& output_unit,
                         const std::string& tool) {
  const auto declared = log.metadata.find("units");
  if (declared == log.metadata.end()) return;
  for (const auto& [unit, side] : {std::pair{input_unit, "inputs"}, std::pair{output_unit, "outputs"}})
    if (!unit.empty() && !mentionsWord(declared->second, unit))
      std::fprintf(stderr, "%s: warning: %s declares '# units: %s', which never says %s: the model's %s are in %s\n",
                   tool.c_str(), log.source.c_str(), declared->second.c_str(), unit.c_str(), side, unit.c_str());
}

void refuseMissingOutputFolder(const std::string& output, const std::string& option, const std::string& tool) {
  if (output.empty() || output == kStandardOutput) return;
  const fs::path folder = fs::path(output).parent_path();
  std::error_code ec;
  if (!folder.empty() && !fs::is_directory(folder, ec))
    throw std::invalid_argument(tool + ": " + option + " " + output + ": the folder " + folder.string() +
                                " does not exist (create it first)");
}

io::Log readLogWithWarnings(const std::string& path, const io::CsvReadOptions& options, const std::string& tool) {
  io::Log log = io::readLog(path, options);
  for (const auto& w : log.warnings) std::fprintf(stderr, "plsa %s: warning: %s\n", tool.c_str(), w.c_str());
  return log;
}

std::vector<io::Log> readLogs(const std::vector<std::string>& paths, const std::vector<std::string>& required,
                              const std::string& tool, const std::string& channel, const std::string& can_profile) {
  io::CsvReadOptions ro;
  ro.required = required;
  ro.lcm_channel = channel;
  ro.can_profile = can_profile;
  std::vector<io::Log> logs;
  for (const auto& p : logPaths(paths, tool, false)) logs.push_back(readLogWithWarnings(p, ro, tool));
  return logs;
}

}  // namespace plsa::app
