// Whole text files in and out for the set-up loaders (models, configs, maps)
// and the tools' outputs, with errors that name the file and what it is.
#pragma once

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace plsa {

/// Throws std::invalid_argument "PATH: cannot open the WHAT" if unreadable.
inline std::string readTextFile(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot open the " + what);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Writes `text` to `path`; throws std::runtime_error "PATH: cannot write the
/// WHAT" if the file cannot be opened or the write fails, so no output is lost unsaid.
inline void writeTextFile(const std::string& path, const std::string& text, const std::string& what) {
  std::ofstream out(path);
  if (out) out << text;
  if (out) out.flush();
  if (!out) throw std::runtime_error(path + ": cannot write the " + what);
}

}  // namespace plsa
