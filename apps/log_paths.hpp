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

#include "plsa/io/csv_log.hpp"

namespace plsa::app {

/// Throws std::invalid_argument naming both when writing `output` (given as
/// `option`) would overwrite one of `inputs` (the same path, a link to it, or
/// the same file under another name): outputs never replace what was read.
void refuseOverwritingInputs(const std::string& output, const std::string& option,
                             const std::vector<std::string>& inputs, const std::string& tool);

/// Throws std::invalid_argument naming `option` when `output`'s folder does
/// not exist (or is not a folder), so a mistyped path fails before the work,
/// not at the write after it. "" and "-" (standard output) pass.
void refuseMissingOutputFolder(const std::string& output, const std::string& option, const std::string& tool);

/// Both checks an output path gets before the work (refuseOverwritingInputs,
/// then refuseMissingOutputFolder).
void checkOutputPath(const std::string& output, const std::string& option, const std::vector<std::string>& inputs,
                     const std::string& tool);

/// Reads a log in any format this build reads (io::logReaders(): CSV, and LCM
/// event logs in a build with LCM), printing its warnings as "TOOL: warning: ...".
io::Log readLogWithWarnings(const std::string& path, const io::CsvReadOptions& options, const std::string& tool);

/// Prints a warning when `log` declares its units (a `# units:` line) and they
/// do not mention the model's input or output unit as a word: the model's
/// numbers would be read in another unit than the log's (a probe's kPa log
/// validated against a bar model without a word).
void warnOfDeclaredUnits(const io::Log& log, const std::string& input_unit, const std::string& output_unit,
                         const std::string& tool);

/// Every log of `paths` (files or folders, logPaths) with readLogWithWarnings,
/// each needing the `required` columns.
std::vector<io::Log> readLogs(const std::vector<std::string>& paths, const std::vector<std::string>& required,
                              const std::string& tool, const std::string& channel, const std::string& can_profile);

}  // namespace plsa::app
