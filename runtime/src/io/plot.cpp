/// @file plot.cpp
/// Line plots as PNG (see plot.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/plot.hpp>

#include "io/file_util.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace duet {
namespace {

cv::Scalar bgr(const Rgb8& c) { return cv::Scalar(c.b, c.g, c.r); }

/// A "nice" tick step (1, 2 or 5 times a power of ten) giving about `target` ticks over span.
double nice_step(double span, int target) {
  const double raw = span / std::max(1, target);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

std::string tick_text(double v, double step) {
  char buf[32];
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step)));
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

void write_plot_png(const std::filesystem::path& path, const std::vector<PlotSeries>& series, const PlotOptions& o) {
  if (o.width_px < 200 || o.width_px > 8000 || o.height_px < 200 || o.height_px > 8000)
    fail(ErrorCode::kInvalidArgument, path.string() + ": plot size must be in [200, 8000] px, got " +
                                          std::to_string(o.width_px) + " x " + std::to_string(o.height_px));
  double xmax = 0.0, ymax = 0.0;
  bool any = false;
  for (const auto& s : series) {
    if (s.x.size() != s.y.size())
      fail(ErrorCode::kInvalidArgument, path.string() + ": series '" + s.label + "' has " + std::to_string(s.x.size()) +
                                            " x values but " + std::to_string(s.y.size()) + " y values");
    if (s.width_px < 1 || s.width_px > 20)
      fail(ErrorCode::kInvalidArgument, path.string() + ": series '" + s.label + "': width_px must be in [1, 20]");
    for (std::size_t i = 0; i < s.x.size(); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) {
        xmax = std::max(xmax, s.x[i]);
        ymax = std::max(ymax, s.y[i]);
        any = true;
      }
  }
  if (!any) fail(ErrorCode::kInvalidArgument, path.string() + ": nothing to plot (no series with a finite point)");
  for (const auto& m : o.markers)
    if (std::isfinite(m.x) && std::isfinite(m.y)) {
      xmax = std::max(xmax, m.x);
      ymax = std::max(ymax, m.y);
    }
  if (xmax <= 0.0) xmax = 1.0;
  if (ymax <= 0.0) ymax = 1.0;
  xmax *= 1.05;
  ymax *= 1.05;

  cv::Mat img(o.height_px, o.width_px, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 80, right = 20, top = o.title.empty() ? 20 : 45, bottom = 60;
  const int pw = o.width_px - left - right, ph = o.height_px - top - bottom;
  auto px = [&](double x, double y) {
    return cv::Point(left + static_cast<int>(std::lround(x / xmax * pw)), top + ph - static_cast<int>(std::lround(y / ymax * ph)));
  };
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  const cv::Scalar grey(200, 200, 200), black(0, 0, 0);
  const double xs = nice_step(xmax, 8), ys = nice_step(ymax, 6);
  for (double x = 0.0; x <= xmax + 1e-9; x += xs) {
    cv::line(img, px(x, 0), px(x, ymax), grey, 1);
    const std::string t = tick_text(x, xs);
    cv::putText(img, t, px(x, 0) + cv::Point(-4 * static_cast<int>(t.size()), 20), font, 0.45, black, 1, cv::LINE_AA);
  }
  for (double y = 0.0; y <= ymax + 1e-9; y += ys) {
    cv::line(img, px(0, y), px(xmax, y), grey, 1);
    const std::string t = tick_text(y, ys);
    cv::putText(img, t, px(0, y) + cv::Point(-10 - 9 * static_cast<int>(t.size()), 5), font, 0.45, black, 1, cv::LINE_AA);
  }
  cv::rectangle(img, px(0, ymax), px(xmax, 0), black, 1);
  if (!o.title.empty()) cv::putText(img, o.title, cv::Point(left, 28), font, 0.65, black, 1, cv::LINE_AA);
  if (!o.x_label.empty())
    cv::putText(img, o.x_label, cv::Point(left + pw / 2 - 4 * static_cast<int>(o.x_label.size()), o.height_px - 15), font, 0.5,
                black, 1, cv::LINE_AA);
  if (!o.y_label.empty()) {
    // Vertical text: draw on a strip and rotate it.
    cv::Mat strip(24, std::max(10, 10 * static_cast<int>(o.y_label.size())), CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(strip, o.y_label, cv::Point(2, 17), font, 0.5, black, 1, cv::LINE_AA);
    cv::Mat rot;
    cv::rotate(strip, rot, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int y0 = std::max(0, top + ph / 2 - rot.rows / 2);
    const int h = std::min(rot.rows, o.height_px - y0);
    rot(cv::Rect(0, 0, rot.cols, h)).copyTo(img(cv::Rect(4, y0, rot.cols, h)));
  }
  for (const auto& s : series) {
    bool have = false;
    cv::Point prev;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        have = false;
        continue;
      }
      const cv::Point p = px(s.x[i], s.y[i]);
      if (have) cv::line(img, prev, p, bgr(s.colour), s.width_px, cv::LINE_AA);
      prev = p;
      have = true;
    }
  }
  for (const auto& m : o.markers) {
    if (!std::isfinite(m.x) || !std::isfinite(m.y)) continue;
    const cv::Point p = px(m.x, m.y);
    cv::drawMarker(img, p, bgr(m.colour), cv::MARKER_TILTED_CROSS, 14, 2);
    cv::putText(img, m.label, p + cv::Point(8, -8), font, 0.45, bgr(m.colour), 1, cv::LINE_AA);
  }
  int ly = top + 20;
  for (const auto& s : series) {
    if (s.label.empty()) continue;
    cv::line(img, cv::Point(left + 15, ly - 5), cv::Point(left + 45, ly - 5), bgr(s.colour), std::max(2, s.width_px), cv::LINE_AA);
    cv::putText(img, s.label, cv::Point(left + 52, ly), font, 0.5, black, 1, cv::LINE_AA);
    ly += 22;
  }
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", img, png)) fail(ErrorCode::kIo, path.string() + ": PNG encoding failed");
  detail::write_file_atomically(path, {std::string_view(reinterpret_cast<const char*>(png.data()), png.size())});
}

}  // namespace duet
