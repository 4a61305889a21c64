// PNG rendering of trajectories and series.
#include <carenav/slam/trajectory_plot.h>
#include <mrpt/img/CImage.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/math/CMatrixDynamic.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

using namespace carenav;
using namespace carenav::slam;
using mrpt::img::TColor;
namespace fs = std::filesystem;

namespace {

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_plot_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

struct Rgb {
  mrpt::math::CMatrix_u8 r, g, b;
  size_t w = 0, h = 0;
};

Rgb load(const std::string& png) {
  mrpt::img::CImage img;
  EXPECT_TRUE(img.loadFromFile(png)) << png;
  Rgb out;
  out.w = img.getWidth();
  out.h = img.getHeight();
  img.getAsRGBMatrices(out.r, out.g, out.b);
  return out;
}

/** The colour as CImage reads it back from a PNG: MRPT's loader and
 *  getAsRGBMatrices() may disagree on the channel order, so the tests compare
 *  against a plain filled image that went the same way. */
TColor readBack(const TColor& c) {
  const std::string png = (scratch() / "calib.png").string();
  mrpt::img::CImage img(4, 4, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, 3, 3, c);
  EXPECT_TRUE(img.saveToFile(png));
  const Rgb im = load(png);
  return TColor(im.r(1, 1), im.g(1, 1), im.b(1, 1));
}

/** Pixels of exactly this colour, and the bounding box of their columns. */
size_t countColor(const Rgb& im, const TColor& drawn, int* col_min = nullptr,
                  int* col_max = nullptr) {
  const TColor c = readBack(drawn);
  size_t n = 0;
  int lo = 1 << 30, hi = -1;
  for (size_t y = 0; y < im.h; ++y)
    for (size_t x = 0; x < im.w; ++x)
      if (im.r(y, x) == c.R && im.g(y, x) == c.G && im.b(y, x) == c.B) {
        ++n;
        lo = std::min(lo, int(x)), hi = std::max(hi, int(x));
      }
  if (col_min) *col_min = lo;
  if (col_max) *col_max = hi;
  return n;
}

/** Grey pixels (r == g == b) with a level in [lo, hi]. */
size_t countGrey(const Rgb& im, int lo, int hi) {
  size_t n = 0;
  for (size_t y = 0; y < im.h; ++y)
    for (size_t x = 0; x < im.w; ++x)
      if (im.r(y, x) == im.g(y, x) && im.g(y, x) == im.b(y, x) && im.r(y, x) >= lo &&
          im.r(y, x) <= hi)
        ++n;
  return n;
}

io::Trajectory2D square(double side, double x0 = 0, double y0 = 0) {
  io::Trajectory2D t;
  for (int k = 0; k <= 40; ++k) {
    const double s = side * (k % 10) / 10.0;
    const int e = k / 10;
    double x = e == 0 ? s : e == 1 ? side : e == 2 ? side - s : 0;
    double y = e == 0 ? 0 : e == 1 ? s : e == 2 ? side : side - s;
    if (k == 40) x = y = 0;
    t.push_back({double(k), x0 + x, y0 + y, 0});
  }
  return t;
}

}  // namespace

TEST(TrajectoryPlot, DrawsBothTracksInTheirColoursFittedToThePicture) {
  const TColor ref_c(70, 70, 70), est_c(214, 39, 40);
  const std::string png = (scratch() / "two.png").string();
  PlotOptions o;
  o.title = "test";
  renderTrajectories(
      {{"reference", square(10), ref_c, 2}, {"estimate", square(10, 0.5, 0.5), est_c, 2}}, png, o);
  const Rgb im = load(png);
  EXPECT_EQ(im.w, 1000u);
  EXPECT_GE(im.h, 300u);
  EXPECT_LE(im.h, 1400u);
  int lo = 0, hi = 0;
  EXPECT_GT(countColor(im, est_c, &lo, &hi), 1000u);
  // Auto-fit: a square spans most of the width, and stays inside it.
  EXPECT_GT(hi - lo, 600);
  EXPECT_GT(lo, 0);
  EXPECT_LT(hi, 999);
  EXPECT_GT(countColor(im, ref_c), 1000u);
}

TEST(TrajectoryPlot, SameScaleOnBothAxes) {
  // A 20 m x 5 m rectangle: its picture must be four times wider than tall.
  io::Trajectory2D t{{0, 0, 0, 0}, {1, 20, 0, 0}, {2, 20, 5, 0}, {3, 0, 5, 0}, {4, 0, 0, 0}};
  const TColor c(0, 0, 255);
  const std::string png = (scratch() / "rect.png").string();
  PlotOptions o;
  o.grid = o.scale_bar = o.mark_start_end = false;
  renderTrajectories({{"r", t, c, 1}}, png, o);
  const Rgb im = load(png);
  const TColor blue = readBack(c);
  int x0 = 1 << 30, x1 = -1, y0 = 1 << 30, y1 = -1;
  for (size_t y = 60; y < im.h; ++y)  // below the legend
    for (size_t x = 0; x < im.w; ++x)
      if (im.r(y, x) == blue.R && im.g(y, x) == blue.G && im.b(y, x) == blue.B) {
        x0 = std::min(x0, int(x)), x1 = std::max(x1, int(x));
        y0 = std::min(y0, int(y)), y1 = std::max(y1, int(y));
      }
  ASSERT_GT(x1, x0);
  ASSERT_GT(y1, y0);
  EXPECT_NEAR(double(x1 - x0) / (y1 - y0), 4.0, 0.1);
}

TEST(TrajectoryPlot, DegenerateInputStillGivesAPicture) {
  const std::string png = (scratch() / "empty.png").string();
  renderTrajectories({}, png);
  EXPECT_EQ(load(png).w, 1000u);
  const double nan = std::nan("");
  renderTrajectories({{"one", {{0, 3, 3, 0}}, std::nullopt, 2},
                      {"nan", {{0, nan, 1, 0}, {1, 2, nan, 0}}, std::nullopt, 2}},
                     png);
  EXPECT_EQ(load(png).w, 1000u);
  EXPECT_THROW(renderTrajectories({}, "/nonexistent_dir/x.png"), std::runtime_error);
}

TEST(TrajectoryPlot, DrawsAnOccupancyGridUnderTheTrack) {
  mrpt::maps::COccupancyGridMap2D map(-5, 5, -5, 5, 0.1);           // unknown everywhere
  for (float x = -4; x < 4; x += 0.05f) map.setPos(x, 4.0f, 0.0f);  // an occupied wall
  const std::string png = (scratch() / "map.png").string();
  PlotOptions o;
  o.background = &map;
  o.scale_bar = o.grid = false;
  renderTrajectories({{"t", square(2), TColor(0, 0, 255), 2}}, png, o);
  const Rgb im = load(png);
  EXPECT_GT(countGrey(im, 0, 60), 500u);        // the wall
  EXPECT_GT(countGrey(im, 140, 155), 100000u);  // unknown cells
  EXPECT_GT(countColor(im, TColor(0, 0, 255)), 100u);
}

TEST(TrajectoryPlot, SeriesPlot) {
  std::vector<double> x, y;
  for (int k = 0; k < 200; ++k) x.push_back(0.1 * k), y.push_back(0.5 + 0.4 * std::sin(0.1 * k));
  const std::string png = (scratch() / "series.png").string();
  SeriesPlotOptions o;
  o.title = "error";
  o.markers.push_back({0.5, "mean"});
  renderSeries(x, y, png, o);
  const Rgb im = load(png);
  EXPECT_EQ(im.w, 1000u);
  EXPECT_EQ(im.h, 400u);
  int lo = 0, hi = 0;
  EXPECT_GT(countColor(im, o.color, &lo, &hi), 500u);
  EXPECT_GT(hi - lo, 800);       // spans the x axis
  renderSeries({}, {}, png, o);  // no data: axes only
  EXPECT_EQ(load(png).w, 1000u);
}
