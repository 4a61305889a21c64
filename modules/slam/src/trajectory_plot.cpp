#include <carenav/common/text.h>
#include <carenav/slam/trajectory_plot.h>
#include <mrpt/img/CImage.h>
#include <mrpt/maps/COccupancyGridMap2D.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace carenav::slam {

using mrpt::img::CImage;
using mrpt::img::TColor;

namespace {

const TColor kWhite(255, 255, 255), kBlack(0, 0, 0), kGrid(225, 225, 225), kAxis(90, 90, 90);
const TColor kPalette[] = {{70, 70, 70},  {31, 119, 180}, {214, 39, 40},
                           {44, 160, 44}, {255, 127, 14}, {148, 103, 189}};

// Bitmap fonts of mrpt::img::CCanvas and their cell sizes.
constexpr int kSmallW = 6, kSmallH = 13;  // "6x13"
constexpr int kBigH = 15;                 // "9x15B"

/** 1, 2 or 5 times a power of ten, at least `raw`. */
double niceStep(double raw) {
  if (!(raw > 0) || !std::isfinite(raw)) return 1;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  const double m = raw / p;
  return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10) * p;
}

/** 1, 2 or 5 times a power of ten, at most `raw`. */
double niceFloor(double raw) {
  if (!(raw > 0) || !std::isfinite(raw)) return 1;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  const double m = raw / p;
  return (m >= 5 ? 5 : m >= 2 ? 2 : 1) * p;
}

std::string num(double v) {
  if (std::abs(v) < 1e-12) v = 0;  // no "-0"
  return formatGeneral(v);
}

int textWidth(const std::string& s) { return static_cast<int>(s.size()) * kSmallW; }

void save(const CImage& img, const std::string& png) {
  if (!img.saveToFile(png)) throw std::runtime_error(png + ": cannot write the PNG picture");
}

void dashedHLine(CImage& img, int x0, int x1, int y, const TColor& c) {
  for (int x = x0; x < x1; x += 12) img.line(x, y, std::min(x + 7, x1), y, c, 1);
}

/** Pixel <-> world mapping of a metric plot area (y up). */
struct View {
  double wx0 = 0, wy1 = 0, scale = 1;  // world left/top edge of the plot area, px per m
  int left = 0, top = 0;
  int px(double x) const { return left + static_cast<int>(std::lround((x - wx0) * scale)); }
  int py(double y) const { return top + static_cast<int>(std::lround((wy1 - y) * scale)); }
};

void drawBackground(CImage& img, const mrpt::maps::COccupancyGridMap2D& map, const View& v, int w,
                    int h) {
  // Sampling the map once per pixel keeps the cost bounded by the picture
  // size, whatever the map resolution.
  for (int r = 0; r < h; ++r) {
    const double y = v.wy1 - (r + 0.5) / v.scale;
    if (y < map.getYMin() || y >= map.getYMax()) continue;
    for (int c = 0; c < w; ++c) {
      const double x = v.wx0 + (c + 0.5) / v.scale;
      if (x < map.getXMin() || x >= map.getXMax()) continue;
      const float p_free = map.getPos(static_cast<float>(x), static_cast<float>(y));
      const auto g = static_cast<uint8_t>(std::clamp(40.0 + 215.0 * p_free, 0.0, 255.0));
      // Unknown (0.5) lands on a light grey; free is white, occupied dark.
      auto* px = img.ptr<uint8_t>(v.left + c, v.top + r);
      px[0] = px[1] = px[2] = g;
    }
  }
}

void drawCross(CImage& img, int x, int y, int r, const TColor& c) {
  img.line(x - r, y - r, x + r, y + r, c, 2);
  img.line(x - r, y + r, x + r, y - r, c, 2);
}

/** The plot area: picture size, margins and the world-to-pixel view. */
struct Frame {
  static constexpr int left = 56, right = 16, top = 48, bottom = 36;
  int W = 0, H = 0, plot_w = 0, plot_h = 0;
  View v;
  double wx1 = 0, wy0 = 0;  // world right and bottom edges of the plot area
};

/** A frame around every finite pose, link end and the background map. */
Frame frameFor(const std::vector<NamedTrajectory>& trajs, const PlotOptions& opts) {
  const double inf = std::numeric_limits<double>::infinity();
  double x0 = inf, y0 = inf, x1 = -inf, y1 = -inf;
  auto grow = [&](double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    x0 = std::min(x0, x), x1 = std::max(x1, x);
    y0 = std::min(y0, y), y1 = std::max(y1, y);
  };
  for (const auto& t : trajs)
    for (const auto& p : t.poses) grow(p.x, p.y);
  for (const auto& [a, b] : opts.links) grow(a.x, a.y), grow(b.x, b.y);
  if (opts.background) {
    grow(opts.background->getXMin(), opts.background->getYMin());
    grow(opts.background->getXMax(), opts.background->getYMax());
  }
  if (!(x0 <= x1)) x0 = y0 = -1, x1 = y1 = 1;  // nothing to draw: a 2 m frame
  // A track shorter than a metre still gets a readable frame.
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  double dx = std::max(x1 - x0, 1.0), dy = std::max(y1 - y0, 1.0);
  const double pad = opts.margin_ratio * std::max(dx, dy);
  dx += 2 * pad, dy += 2 * pad;

  const int W = std::max(opts.width, 300);
  Frame f;
  const int left = Frame::left, right = Frame::right, top = Frame::top, bottom = Frame::bottom;
  const int plot_w = W - left - right;
  int H = opts.height;
  if (H <= 0) H = std::clamp(static_cast<int>(dy * plot_w / dx) + top + bottom, 300, 1400);
  H = std::max(H, top + bottom + 100);
  const int plot_h = H - top - bottom;

  View v;
  v.scale = std::min(plot_w / dx, plot_h / dy);
  v.left = left;
  v.top = top;
  v.wx0 = cx - 0.5 * plot_w / v.scale;
  v.wy1 = cy + 0.5 * plot_h / v.scale;
  const double wx1 = v.wx0 + plot_w / v.scale, wy0 = v.wy1 - plot_h / v.scale;

  f.W = W, f.H = H, f.plot_w = plot_w, f.plot_h = plot_h, f.v = v, f.wx1 = wx1, f.wy0 = wy0;
  return f;
}

/** Axis numbers every nice step, and grid lines where no map is drawn. */
void drawGrid(CImage& img, const Frame& f, const PlotOptions& opts) {
  const View& v = f.v;
  const int left = Frame::left, top = Frame::top, plot_w = f.plot_w, plot_h = f.plot_h;
  const double wx1 = f.wx1, wy0 = f.wy0;
  const double step = niceStep(std::max(wx1 - v.wx0, v.wy1 - wy0) / 10);
  for (double gx = std::ceil(v.wx0 / step) * step; gx <= wx1; gx += step) {
    const int x = v.px(gx);
    if (!opts.background) img.line(x, top, x, top + plot_h, kGrid, 1);
    const std::string s = num(gx);
    img.textOut(x - textWidth(s) / 2, top + plot_h + 4, s, kAxis);
  }
  for (double gy = std::ceil(wy0 / step) * step; gy <= v.wy1; gy += step) {
    const int y = v.py(gy);
    if (!opts.background) img.line(left, y, left + plot_w, y, kGrid, 1);
    const std::string s = num(gy);
    img.textOut(left - 4 - textWidth(s), y - kSmallH / 2, s, kAxis);
  }
  img.textOut(left + plot_w - textWidth("x [m]"), top + plot_h + 4 + kSmallH + 2, "x [m]", kAxis);
  img.textOut(4, top - kSmallH - 4, "y [m]", kAxis);
}

/** Links, then every trajectory, then start and end marks. */
void drawTracks(CImage& img, const View& v, const std::vector<NamedTrajectory>& trajs,
                const std::vector<TColor>& colors, const PlotOptions& opts) {
  for (const auto& [a, b] : opts.links) {
    if (!std::isfinite(a.x + a.y + b.x + b.y)) continue;
    img.line(v.px(a.x), v.py(a.y), v.px(b.x), v.py(b.y), opts.link_color, 1);
  }

  for (size_t k = 0; k < trajs.size(); ++k) {
    const auto& t = trajs[k].poses;
    for (size_t i = 1; i < t.size(); ++i) {
      if (!std::isfinite(t[i - 1].x + t[i - 1].y + t[i].x + t[i].y)) continue;
      img.line(v.px(t[i - 1].x), v.py(t[i - 1].y), v.px(t[i].x), v.py(t[i].y), colors[k],
               std::max(1u, trajs[k].line_width));
    }
  }
  if (opts.mark_start_end) {
    for (size_t k = 0; k < trajs.size(); ++k) {
      const auto& t = trajs[k].poses;
      const auto first = std::find_if(
          t.begin(), t.end(), [](const io::TimedPose2D& p) { return std::isfinite(p.x + p.y); });
      const auto last = std::find_if(
          t.rbegin(), t.rend(), [](const io::TimedPose2D& p) { return std::isfinite(p.x + p.y); });
      if (first == t.end()) continue;
      img.drawCircle(v.px(first->x), v.py(first->y), 7, colors[k], 2);
      drawCross(img, v.px(last->x), v.py(last->y), 6, colors[k]);
    }
  }
}

/** Title, then the legend on the line below it, both above the plot area. */
void drawLegend(CImage& img, const Frame& f, const std::vector<NamedTrajectory>& trajs,
                const std::vector<TColor>& colors, const PlotOptions& opts) {
  const View& v = f.v;
  const int left = Frame::left, top = Frame::top, plot_w = f.plot_w;
  const double wx1 = f.wx1;
  int lx = left;
  const int ly = top - kSmallH - 6;
  if (!opts.title.empty()) {
    img.selectTextFont("9x15B");
    img.textOut(left, 4, opts.title, kBlack);
    img.selectTextFont("6x13");
  }
  const int legend_y = opts.title.empty() ? ly : std::max(ly, 4 + kBigH + 2);
  for (size_t k = 0; k < trajs.size(); ++k) {
    const int mid = legend_y + kSmallH / 2;
    img.line(lx, mid, lx + 24, mid, colors[k], 3);
    img.textOut(lx + 30, legend_y, trajs[k].name, kBlack);
    lx += 30 + textWidth(trajs[k].name) + 18;
  }
  if (opts.mark_start_end && !trajs.empty()) {
    const int mid = legend_y + kSmallH / 2;
    img.drawCircle(lx + 6, mid, 6, kAxis, 2);
    img.textOut(lx + 16, legend_y, "start", kAxis);
    lx += 16 + textWidth("start") + 14;
    drawCross(img, lx + 5, mid, 5, kAxis);
    img.textOut(lx + 16, legend_y, "end", kAxis);
  }
  // Scale bar at the right end of the legend line, so it never hides data.
  if (opts.scale_bar) {
    const double len = niceFloor((wx1 - v.wx0) / 5);
    const int bar = static_cast<int>(std::lround(len * v.scale));
    const std::string s = num(len) + " m";
    const int bx1 = left + plot_w, bx0 = bx1 - bar, by = legend_y + kSmallH / 2;
    img.filledRectangle(bx0, by - 2, bx1, by + 2, kBlack);
    img.line(bx0, by - 6, bx0, by + 6, kBlack, 1);
    img.line(bx1, by - 6, bx1, by + 6, kBlack, 1);
    img.textOut(bx0 - 8 - textWidth(s), legend_y, s, kBlack);
  }
}

}  // namespace

void renderTrajectories(const std::vector<NamedTrajectory>& trajs, const std::string& png,
                        const PlotOptions& opts) {
  const Frame f = frameFor(trajs, opts);
  CImage img(f.W, f.H, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, f.W - 1, f.H - 1, kWhite);
  if (opts.background) drawBackground(img, *opts.background, f.v, f.plot_w, f.plot_h);
  img.selectTextFont("6x13");
  if (opts.grid) drawGrid(img, f, opts);
  img.rectangle(Frame::left, Frame::top, Frame::left + f.plot_w, Frame::top + f.plot_h, kAxis, 1);
  std::vector<TColor> colors;
  for (size_t k = 0; k < trajs.size(); ++k)
    colors.push_back(trajs[k].color.value_or(kPalette[k % std::size(kPalette)]));
  drawTracks(img, f.v, trajs, colors, opts);
  drawLegend(img, f, trajs, colors, opts);
  save(img, png);
}

void renderSeries(const std::vector<double>& xs, const std::vector<double>& ys,
                  const std::string& png, const SeriesPlotOptions& opts) {
  const double inf = std::numeric_limits<double>::infinity();
  double x0 = inf, x1 = -inf, y0 = inf, y1 = -inf;
  const size_t n = std::min(xs.size(), ys.size());
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(xs[i]) || !std::isfinite(ys[i])) continue;
    x0 = std::min(x0, xs[i]), x1 = std::max(x1, xs[i]);
    y0 = std::min(y0, ys[i]), y1 = std::max(y1, ys[i]);
  }
  for (const auto& m : opts.markers)
    if (std::isfinite(m.y)) y0 = std::min(y0, m.y), y1 = std::max(y1, m.y);
  if (!(x0 <= x1)) x0 = 0, x1 = 1;
  if (!(y0 <= y1)) y0 = 0, y1 = 1;
  if (y0 >= 0) y0 = 0;  // errors: the axis starts at zero
  if (x1 - x0 < 1e-9) x0 -= 0.5, x1 += 0.5;
  if (y1 - y0 < 1e-12) y1 = y0 + 1;
  y1 += 0.08 * (y1 - y0);

  const int W = std::max(opts.width, 300), H = std::max(opts.height, 200);
  const int left = 64, right = 20, top = 40, bottom = 44;
  const int pw = W - left - right, ph = H - top - bottom;
  auto px = [&](double x) {
    return left + static_cast<int>(std::lround((x - x0) / (x1 - x0) * pw));
  };
  auto py = [&](double y) {
    return top + static_cast<int>(std::lround((y1 - y) / (y1 - y0) * ph));
  };

  CImage img(W, H, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, W - 1, H - 1, kWhite);
  img.selectTextFont("6x13");
  const double sx = niceStep((x1 - x0) / 10), sy = niceStep((y1 - y0) / 6);
  for (double gx = std::ceil(x0 / sx) * sx; gx <= x1 + 1e-9 * sx; gx += sx) {
    img.line(px(gx), top, px(gx), top + ph, kGrid, 1);
    const std::string s = num(gx);
    img.textOut(px(gx) - textWidth(s) / 2, top + ph + 4, s, kAxis);
  }
  for (double gy = std::ceil(y0 / sy) * sy; gy <= y1 + 1e-9 * sy; gy += sy) {
    img.line(left, py(gy), left + pw, py(gy), kGrid, 1);
    const std::string s = num(gy);
    img.textOut(left - 4 - textWidth(s), py(gy) - kSmallH / 2, s, kAxis);
  }
  img.rectangle(left, top, left + pw, top + ph, kAxis, 1);
  if (!opts.x_label.empty())
    img.textOut(left + (pw - textWidth(opts.x_label)) / 2, top + ph + 6 + kSmallH, opts.x_label,
                kAxis);
  if (!opts.y_label.empty()) img.textOut(4, top - kSmallH - 4, opts.y_label, kAxis);

  for (size_t i = 1; i < n; ++i) {
    if (!std::isfinite(xs[i - 1] + ys[i - 1] + xs[i] + ys[i])) continue;
    img.line(px(xs[i - 1]), py(ys[i - 1]), px(xs[i]), py(ys[i]), opts.color, 1);
  }
  for (const auto& m : opts.markers) {
    if (!std::isfinite(m.y)) continue;
    dashedHLine(img, left, left + pw, py(m.y), kBlack);
    img.textOut(left + pw - textWidth(m.label) - 4, py(m.y) - kSmallH - 2, m.label, kBlack);
  }
  if (!opts.title.empty()) {
    img.selectTextFont("9x15B");
    img.textOut(left, 6, opts.title, kBlack);
  }
  save(img, png);
}

}  // namespace carenav::slam
