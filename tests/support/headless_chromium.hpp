// A page opened in headless Chromium, for tests of what a report's reader
// sees: the DOM after the page's scripts ran.
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace plsa::test {

struct RenderedPage {
  bool browser_found = false;  ///< false: /usr/bin/chromium is not installed
  int status = -1;             ///< the browser's exit status
  std::string dom;             ///< the DOM after the page's scripts ran
};

inline RenderedPage renderInChromium(const std::string& html) {
  namespace fs = std::filesystem;
  RenderedPage page;
  const char* chromium = "/usr/bin/chromium";
  page.browser_found = fs::exists(chromium);
  if (!page.browser_found) return page;
  static int serial = 0;
  const fs::path dir =
      fs::temp_directory_path() / ("plsa_page_" + std::to_string(::getpid()) + "_" + std::to_string(++serial));
  fs::create_directories(dir);
  std::ofstream(dir / "page.html") << html;
  const std::string cmd = std::string(chromium) +
                          " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
                          " --disable-background-networking --disable-component-update --disable-sync"
                          " --user-data-dir=" +
                          (dir / "profile").string() + " --dump-dom file://" + (dir / "page.html").string() + " > " +
                          (dir / "dom.html").string() + " 2>/dev/null";
  page.status = std::system(cmd.c_str());
  std::stringstream dom;
  dom << std::ifstream(dir / "dom.html").rdbuf();
  page.dom = dom.str();
  fs::remove_all(dir);
  return page;
}

/// How often `what` occurs in `text`.
inline std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace plsa::test
