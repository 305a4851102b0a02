// Whole files in and out for the set-up loaders (models, configs, maps) and
// the tools' outputs, with errors that name the file and what it is.
// Reads are bounded (a device file or a mistaken path cannot grow memory
// without end); writes are atomic (a temporary file in the same folder,
// flushed to disk, then renamed over the target), so a crash mid-write
// leaves the previous file whole.
#pragma once

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace plsa {

/// Largest file a set-up loader reads (model, simulator configuration,
/// signal map): 64 MiB, about a hundred times the largest model plsa writes.
inline constexpr std::size_t kMaxTextFileBytes = std::size_t{64} << 20;

/// Throws std::invalid_argument when `path` holds a NUL byte: the system
/// would read it as the shorter name before the NUL, another file (a Python
/// or other caller's string can hold one; a command line cannot).
inline void refuseNulInPath(const std::string& path) {
  if (path.find('\0') != std::string::npos)
    throw std::invalid_argument("a path with a NUL byte after '" + std::string(path.c_str()) + "' is not a file name");
}

/// Reads at most `max_bytes`; throws std::invalid_argument "PATH: cannot open
/// the WHAT" if unreadable, and "PATH: the WHAT is larger than ..." beyond it
/// (before the text grows past the limit).
inline std::string readTextFile(const std::string& path, const std::string& what,
                                std::size_t max_bytes = kMaxTextFileBytes) {
  refuseNulInPath(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot open the " + what);
  std::string text;
  char chunk[1 << 16];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
    if (text.size() + static_cast<std::size_t>(in.gcount()) > max_bytes)
      throw std::invalid_argument(path + ": the " + what + " is larger than " + std::to_string(max_bytes >> 20) +
                                  " MiB, the most plsa reads (is this the right file?)");
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw std::invalid_argument(path + ": cannot read the " + what);
  return text;
}

namespace detail {

inline void writeAll(int fd, std::string_view bytes, const std::string& path, const std::string& what) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error(path + ": cannot write the " + what + ": " + std::strerror(errno));
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
}

inline std::string folderOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

}  // namespace detail

/// The path that means standard output, as command-line tools take it.
inline constexpr const char* kStandardOutput = "-";

/// Writes what `produce` emits to `path` atomically: into a temporary file
/// beside it, fsync'ed, then renamed over `path` (and the folder fsync'ed).
/// `produce(emit)` calls `emit(std::string_view)` for each piece in order, so
/// a large output is written as it is made rather than held whole. A path
/// that exists and is not a regular file (a FIFO, /dev/null) is written in
/// place; "-" (kStandardOutput) is standard output. Throws
/// std::runtime_error "PATH: cannot write the WHAT: reason"; on any failure
/// the temporary file is removed and `path` is left as it was.
template <class Produce>
void writeFileAtomicallyFrom(const std::string& path, const std::string& what, Produce&& produce) {
  refuseNulInPath(path);
  if (path == kStandardOutput) {
    std::fflush(stdout);  // whatever was printed before comes first
    produce([&](std::string_view piece) { detail::writeAll(STDOUT_FILENO, piece, "standard output", what); });
    return;
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error(path + ": cannot write the " + what + ": " + std::strerror(errno));
    try {
      produce([&](std::string_view piece) { detail::writeAll(fd, piece, path, what); });
    } catch (...) {
      ::close(fd);
      throw;
    }
    ::close(fd);
    return;
  }
  const std::string folder = detail::folderOf(path);
  const std::string base = path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
  std::string tmp = (folder == "/" ? "" : folder) + "/." + base + ".tmp-XXXXXX";
  int fd = ::mkstemp(tmp.data());
  if (fd < 0) throw std::runtime_error(path + ": cannot write the " + what + ": " + std::strerror(errno));
  auto fail = [&](int err) {
    if (fd >= 0) ::close(fd);
    ::unlink(tmp.c_str());
    throw std::runtime_error(path + ": cannot write the " + what + ": " + std::strerror(err));
  };
  // mkstemp makes the file 0600; give it the mode a plain open would (0666 less the umask).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, static_cast<mode_t>(0666 & ~mask));
  try {
    produce([&](std::string_view piece) { detail::writeAll(fd, piece, path, what); });
  } catch (const std::runtime_error&) {
    fail(errno);
  } catch (...) {  // the producer's own failure: no file is left behind either
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  if (::fsync(fd) != 0) fail(errno);
  const int closed = ::close(fd);
  fd = -1;
  if (closed != 0) fail(errno);
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error(path + ": cannot write the " + what + ": " + std::strerror(err));
  }
  const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);  // the rename itself reaches the disk
    ::close(dir);
  }
}

/// Writes `bytes` to `path` atomically (writeFileAtomicallyFrom, in one piece).
inline void writeFileAtomically(const std::string& path, std::string_view bytes, const std::string& what) {
  writeFileAtomicallyFrom(path, what, [&](const auto& emit) { emit(bytes); });
}

/// Writes `text` to `path` atomically (writeFileAtomically).
inline void writeTextFile(const std::string& path, const std::string& text, const std::string& what) {
  writeFileAtomically(path, text, what);
}

}  // namespace plsa
