// Reading a whole text file for the set-up loaders (models, configs, maps),
// with an error that names the file and what it was meant to be.
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

}  // namespace plsa
