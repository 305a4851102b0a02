#include "plsa/identify/output_frame_choice.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>

namespace plsa::identify {
namespace {

std::string lowered(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool namedAs(const std::string& name, std::initializer_list<const char*> stems) {
  const std::string n = lowered(name);
  return std::any_of(stems.begin(), stems.end(), [&](const char* s) { return n.find(s) != std::string::npos; });
}

bool isBending(const std::string& name) { return namedAs(name, {"bend", "theta", "inclin"}); }
bool isSteering(const std::string& name) { return namedAs(name, {"steer", "azimuth", "phi"}); }

// Share of the first column's samples below -0.5 deg over every log.
double negativeBendingShare(const std::vector<Eigen::MatrixXd>& Y) {
  Eigen::Index below = 0, all = 0;
  for (const auto& y : Y) {
    if (y.cols() < 1) continue;
    below += (y.col(0).array() < -0.5).count();
    all += y.rows();
  }
  return all == 0 ? 0.0 : static_cast<double>(below) / static_cast<double>(all);
}

}  // namespace

OutputFrameChoice chooseOutputFrame(const std::vector<std::string>& outputs, const std::vector<Eigen::MatrixXd>& Y) {
  OutputFrameChoice c;
  if (outputs.size() != 2) {
    c.reason = "outputs fitted as logged (the tip frame takes exactly two outputs, bending and steering)";
    return c;
  }
  const std::string pair = "'" + outputs[0] + "' and '" + outputs[1] + "'";
  if (isSteering(outputs[0]) && isBending(outputs[1])) {
    c.reason = "outputs fitted as logged: " + pair +
               " look like a tip's steering and bending angles in that order; "
               "list the bending angle first (--outputs " +
               outputs[1] + "," + outputs[0] + ") to fit them in the tip frame";
    return c;
  }
  if (!(isBending(outputs[0]) && isSteering(outputs[1]))) {
    c.reason = "outputs " + pair +
               " fitted as logged; if they are a tip's bending and steering angles (deg), "
               "--output-frame tip_cartesian fits them in the tip frame, usually better";
    return c;
  }
  const double negative = negativeBendingShare(Y);
  if (negative > 0.01) {
    char share[32];
    std::snprintf(share, sizeof share, "%.1f%%", 100.0 * negative);
    c.reason = "outputs " + pair + " fitted as logged: they are named as bending and steering angles, but " + share +
               " of '" + outputs[0] +
               "' lies below -0.5 deg, and a bending angle is never negative "
               "(--output-frame tip_cartesian to fit them in the tip frame anyway)";
    return c;
  }
  c.frame = OutputFrame::kTipCartesian;
  c.reason = "outputs " + pair +
             " read as a tip's bending and steering angles (deg): fitted in the tip frame "
             "(--output-frame as_logged to fit them as logged)";
  return c;
}

}  // namespace plsa::identify
