#pragma once
/// @file plot.hpp
/// Line plots as PNG pictures (run curves: the time-area curve of the paper's Fig. 10), drawn
/// with OpenCV: axes with ticks at 1-2-5 steps, a legend, optional reference markers.
///
/// Errors: duet::Error(kInvalidArgument) for an empty plot (no series with a finite point),
/// a size out of [200, 8000] px, a non-finite axis range; kIo when the file cannot be written
/// (written to a temporary sibling, then renamed).
/// Thread safety: reentrant.
#include <duet/kernels/types.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace duet {

struct PlotSeries {
  std::string label;             ///< legend text ("" = not in the legend)
  std::vector<double> x, y;      ///< same length; non-finite points break the line
  Rgb8 colour{30, 90, 200};
  int width_px = 2;              ///< line width [px], [1, 20]
};

/// A labelled marker, e.g. the paper's result (196 s, 31.0 m^2).
struct PlotMarker {
  std::string label;
  double x = 0.0, y = 0.0;
  Rgb8 colour{200, 40, 40};
};

struct PlotOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width_px = 900;   ///< [200, 8000]
  int height_px = 600;  ///< [200, 8000]
  std::vector<PlotMarker> markers;
};

/// Draws the series (axes from 0 to the largest x and y of the data and markers, padded 5 %)
/// and writes a PNG.
void write_plot_png(const std::filesystem::path& path, const std::vector<PlotSeries>& series, const PlotOptions& options);

}  // namespace duet
