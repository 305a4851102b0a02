#include "plsa/identify/output_frame_choice.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "plsa/core/check.hpp"

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

// Share of the first column's samples below -0.5 deg over every log, the
// angles in `unit`.
double negativeBendingShare(const std::vector<Eigen::MatrixXd>& Y, const std::string& unit) {
  const double floor = -0.5 * kRadPerDeg / radiansPerAngleUnit(unit);
  Eigen::Index below = 0, all = 0;
  for (const auto& y : Y) {
    if (y.cols() < 1) continue;
    below += (y.col(0).array() < floor).count();
    all += y.rows();
  }
  return all == 0 ? 0.0 : static_cast<double>(below) / static_cast<double>(all);
}

// The largest magnitude in the first two columns over every log.
double largestAngle(const std::vector<Eigen::MatrixXd>& Y) {
  double largest = 0.0;
  for (const auto& y : Y)
    if (y.size() > 0)
      largest = std::max(largest, y.leftCols(std::min<Eigen::Index>(2, y.cols())).cwiseAbs().maxCoeff());
  return largest;
}

}  // namespace

std::string chooseAngleUnit(const std::vector<std::string>& outputs, const std::vector<Eigen::MatrixXd>& Y,
                            const std::optional<std::string>& given, std::string& why) {
  if (given) {
    radiansPerAngleUnit(*given);  // refuses any other unit, naming it
    why = "as given";
    return *given;
  }
  const bool deg = namedAs(outputs.at(0), {"deg"}) || namedAs(outputs.at(1), {"deg"});
  const bool rad = namedAs(outputs.at(0), {"rad"}) || namedAs(outputs.at(1), {"rad"});
  PLSA_CHECK(!(deg && rad), "identify: the outputs '" + outputs[0] + "' and '" + outputs[1] +
                                "' name different angle units; log a tip's bending and steering in one unit, "
                                "or give --angle-unit");
  if (deg || rad) {
    why = "as the names say";
    return deg ? "deg" : "rad";
  }
  // A radian angle stays within +-pi or [0, 2 pi) (the margin takes a wrap's overshoot and noise).
  const double largest = largestAngle(Y);
  if (!std::isfinite(largest) || largest > 2.0 * kPi + 0.05) {
    why = "values beyond 2 pi";
    return "deg";
  }
  why = "every value within 2 pi and no unit in the names; --angle-unit deg if they are degrees";
  return "rad";
}

OutputFrameChoice chooseOutputFrame(const std::vector<std::string>& outputs, const std::vector<Eigen::MatrixXd>& Y,
                                    const std::optional<std::string>& unit) {
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
  std::string unit_why;
  const std::string angle_unit = chooseAngleUnit(outputs, Y, unit, unit_why);
  const double negative = negativeBendingShare(Y, angle_unit);
  if (negative > 0.01) {
    char share[32];
    std::snprintf(share, sizeof share, "%.1f%%", 100.0 * negative);
    c.reason = "outputs " + pair + " fitted as logged: they are named as bending and steering angles, but " + share +
               " of '" + outputs[0] + "' lies below -0.5 deg" +
               (angle_unit == "rad" ? std::string(" (-0.00873 rad)") : std::string()) +
               ", and a bending angle is never negative "
               "(--output-frame tip_cartesian to fit them in the tip frame anyway)";
    return c;
  }
  c.frame = OutputFrame::kTipCartesian;
  c.angle_unit = angle_unit;
  c.angle_unit_reason = unit_why;
  c.reason = "outputs " + pair + " read as a tip's bending and steering angles in " + angle_unit + " (" + unit_why +
             "): fitted in the tip frame (--output-frame as_logged to fit them as logged)";
  return c;
}

}  // namespace plsa::identify
