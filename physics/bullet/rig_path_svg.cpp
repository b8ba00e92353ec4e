// SVG plot of the camera head's path, commanded against physical (top view,
// side view, deviation over time); docs/rig-dynamics.md "Plots".
#include "physics/bullet/rig_path_svg.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "base/xml_escape.h"

namespace moco::physics {
namespace {

constexpr size_t kMaxPoints = 2000;
// Coordinates beyond this (metres, millimetres, seconds) are not plotted.
constexpr double kMaxMagnitude = 1e6;
constexpr int kMaxTicks = 20;

bool Plottable(double v) { return std::isfinite(v) && std::abs(v) <= kMaxMagnitude; }
constexpr const char* kCommandedColour = "#1f77b4";
constexpr const char* kPhysicalColour = "#d62728";

std::string Num(double v, const char* format = "%.2f") {
  char buf[48];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

struct Series {
  std::string id;
  const char* colour;
  bool dashed;
  std::vector<double> xs, ys;
};

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!Plottable(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  // An empty or degenerate range grows to a usable one around its middle.
  void Settle(double min_span) {
    if (lo > hi) lo = hi = 0;
    const double span = hi - lo;
    if (span < min_span) {
      const double mid = (lo + hi) / 2;
      lo = mid - min_span / 2;
      hi = mid + min_span / 2;
    } else {
      lo -= span * 0.05;
      hi += span * 0.05;
    }
  }
};

double NiceStep(double span) {
  const double raw = span / 5;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (raw <= m * mag) return m * mag;
  }
  return 10 * mag;
}

// Draws one panel into `out`: frame, ticks, axis titles and the series.
void Panel(std::string& out, const std::string& id, double left, double top, double width,
           double height, const std::string& x_title, const std::string& y_title,
           const std::string& panel_title, std::vector<Series> series, bool equal_scale,
           double min_span) {
  Range rx, ry;
  for (const Series& s : series) {
    for (double x : s.xs) rx.Add(x);
    for (double y : s.ys) ry.Add(y);
  }
  rx.Settle(min_span);
  ry.Settle(min_span);
  double sx = width / (rx.hi - rx.lo);
  double sy = height / (ry.hi - ry.lo);
  if (equal_scale) {
    const double s = std::min(sx, sy);
    const double grow_x = (width / s - (rx.hi - rx.lo)) / 2;
    const double grow_y = (height / s - (ry.hi - ry.lo)) / 2;
    rx.lo -= grow_x;
    rx.hi += grow_x;
    ry.lo -= grow_y;
    ry.hi += grow_y;
    sx = sy = s;
  }
  auto px = [&](double x) { return left + (x - rx.lo) * sx; };
  auto py = [&](double y) { return top + height - (y - ry.lo) * sy; };

  out += "<g id=\"" + id + "\">\n";
  out += "<text x=\"" + Num(left + width / 2) + "\" y=\"" + Num(top - 8) +
         "\" text-anchor=\"middle\" font-size=\"13\">" + base::XmlEscape(panel_title) + "</text>\n";
  out += "<rect x=\"" + Num(left) + "\" y=\"" + Num(top) + "\" width=\"" + Num(width) +
         "\" height=\"" + Num(height) + "\" fill=\"none\" stroke=\"#888\"/>\n";
  const double step_x = NiceStep(rx.hi - rx.lo);
  const double first_x = std::ceil(rx.lo / step_x) * step_x;
  for (int k = 0; k < kMaxTicks && first_x + k * step_x <= rx.hi; ++k) {
    const double t = first_x + k * step_x;
    const double x = px(t);
    out += "<line x1=\"" + Num(x) + "\" y1=\"" + Num(top + height) + "\" x2=\"" + Num(x) +
           "\" y2=\"" + Num(top + height + 5) + "\" stroke=\"#888\"/>\n";
    out += "<text x=\"" + Num(x) + "\" y=\"" + Num(top + height + 18) +
           "\" text-anchor=\"middle\">" + Num(std::abs(t) < step_x / 1e6 ? 0.0 : t, "%.4g") +
           "</text>\n";
  }
  const double step_y = NiceStep(ry.hi - ry.lo);
  const double first_y = std::ceil(ry.lo / step_y) * step_y;
  for (int k = 0; k < kMaxTicks && first_y + k * step_y <= ry.hi; ++k) {
    const double t = first_y + k * step_y;
    const double y = py(t);
    out += "<line x1=\"" + Num(left - 5) + "\" y1=\"" + Num(y) + "\" x2=\"" + Num(left) +
           "\" y2=\"" + Num(y) + "\" stroke=\"#888\"/>\n";
    out += "<text x=\"" + Num(left - 8) + "\" y=\"" + Num(y + 4) + "\" text-anchor=\"end\">" +
           Num(std::abs(t) < step_y / 1e6 ? 0.0 : t, "%.4g") + "</text>\n";
  }
  out += "<text x=\"" + Num(left + width / 2) + "\" y=\"" + Num(top + height + 36) +
         "\" text-anchor=\"middle\">" + base::XmlEscape(x_title) + "</text>\n";
  const double ty = top + height / 2;
  out += "<text x=\"" + Num(left - 48) + "\" y=\"" + Num(ty) + "\" text-anchor=\"middle\"" +
         " transform=\"rotate(-90 " + Num(left - 48) + " " + Num(ty) + ")\">" +
         base::XmlEscape(y_title) + "</text>\n";
  for (const Series& s : series) {
    std::string d;
    const size_t n = s.xs.size();
    const size_t stride = n > kMaxPoints ? (n + kMaxPoints - 1) / kMaxPoints : 1;
    for (size_t i = 0; i < n; i += stride) {
      const size_t k = (i + stride >= n) ? n - 1 : i;  // always end on the last point
      if (!Plottable(s.xs[k]) || !Plottable(s.ys[k])) continue;
      d += (d.empty() ? "M" : " L") + Num(px(s.xs[k])) + " " + Num(py(s.ys[k]));
    }
    // An empty series still gets its element (a path with no data draws nothing).
    out += "<path id=\"" + s.id + "\" d=\"" + d + "\" fill=\"none\" stroke=\"" + s.colour +
           "\" stroke-width=\"1.5\"" + (s.dashed ? " stroke-dasharray=\"6 4\"" : "") + "/>\n";
  }
  out += "</g>\n";
}

}  // namespace

std::string RigPathSvg(const std::vector<RigPathSample>& samples, std::string_view title) {
  constexpr double kWidth = 1000, kHeight = 760;
  std::vector<double> cx, cy, cz, fx, fy, fz, t, dev_mm;
  for (const RigPathSample& s : samples) {
    cx.push_back(s.commanded_m[0]);
    cy.push_back(s.commanded_m[1]);
    cz.push_back(s.commanded_m[2]);
    fx.push_back(s.physical_m[0]);
    fy.push_back(s.physical_m[1]);
    fz.push_back(s.physical_m[2]);
    t.push_back(s.time_s);
    const double dx = s.physical_m[0] - s.commanded_m[0];
    const double dy = s.physical_m[1] - s.commanded_m[1];
    const double dz = s.physical_m[2] - s.commanded_m[2];
    dev_mm.push_back(1e3 * std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  std::string out;
  out += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + Num(kWidth, "%.0f") +
         "\" height=\"" + Num(kHeight, "%.0f") + "\" viewBox=\"0 0 " + Num(kWidth, "%.0f") + " " +
         Num(kHeight, "%.0f") + "\" font-family=\"sans-serif\" font-size=\"11\">\n";
  out += "<title>" + base::XmlEscape(title) + "</title>\n";
  out += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  out += "<text x=\"" + Num(kWidth / 2) + "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">" +
         base::XmlEscape(title) + "</text>\n";
  // Legend.
  out += "<g id=\"legend\">\n";
  out += std::string("<line x1=\"360\" y1=\"40\" x2=\"400\" y2=\"40\" stroke=\"") +
         kCommandedColour + "\" stroke-width=\"1.5\" stroke-dasharray=\"6 4\"/>\n";
  out += "<text x=\"406\" y=\"44\">commanded (ideal kinematics)</text>\n";
  out += std::string("<line x1=\"580\" y1=\"40\" x2=\"620\" y2=\"40\" stroke=\"") +
         kPhysicalColour + "\" stroke-width=\"1.5\"/>\n";
  out += "<text x=\"626\" y=\"44\">physical (simulated)</text>\n";
  out += "</g>\n";

  Panel(out, "top-view", 90, 80, 380, 380, "x, east-west [m]", "y, along the track [m]", "top view",
        {{"top-commanded", kCommandedColour, true, cx, cy},
         {"top-physical", kPhysicalColour, false, fx, fy}},
        true, 0.1);
  Panel(out, "side-view", 590, 80, 380, 380, "y, along the track [m]", "z, up [m]", "side view",
        {{"side-commanded", kCommandedColour, true, cy, cz},
         {"side-physical", kPhysicalColour, false, fy, fz}},
        true, 0.1);
  Panel(out, "deviation", 90, 540, 880, 150, "time [s]", "|physical - commanded| [mm]",
        "deviation of the nodal point", {{"deviation-mm", kPhysicalColour, false, t, dev_mm}},
        false, 1.0);
  out += "</svg>\n";
  return out;
}

}  // namespace moco::physics
