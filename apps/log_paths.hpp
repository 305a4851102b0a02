// Log paths as the tools take them: files, or folders of .csv / .lcmlog
// files. One file given twice is refused: a log would be both trained and
// scored on, or weigh double, without a word.
#pragma once

#include <string>
#include <vector>

namespace plsa::app {

/// Files in the order given, a folder's files sorted in its place; throws
/// naming a path that is neither a file nor (with `folders`) a folder, a
/// folder without logs, and a file reached twice.
std::vector<std::string> logPaths(const std::vector<std::string>& paths, const std::string& tool, bool folders);

}  // namespace plsa::app
