// PNG pictures of occupancy grids with overlays and a scale bar.
#include <carenav/common/errors.h>
#include <carenav/io/map_render.h>

#include <mrpt/img/TColor.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "map_io_internal.h"

namespace carenav::io {

namespace {

using mrpt::img::TColor;

constexpr uint8_t kFree = 255, kOccupied = 0, kUnknown = 190;

TColor toColor(const Rgb& c) { return TColor(c.r, c.g, c.b); }

// Text on a white box, so it reads over any map.
void label(mrpt::img::CImage& img, int x, int y, const std::string& text, const TColor& colour) {
  constexpr int kCharW = 9, kCharH = 15;  // CCanvas' default 9x15 font
  const int w = static_cast<int>(text.size()) * kCharW;
  img.filledRectangle(x - 2, y - 2, x + w + 1, y + kCharH + 1, TColor(255, 255, 255));
  img.textOut(x, y, text, colour);
}

std::string metresText(double m) {
  char b[32];
  if (m >= 1)
    std::snprintf(b, sizeof b, "%g m", m);
  else
    std::snprintf(b, sizeof b, "%g cm", m * 100);
  return b;
}

// The largest of 1-2-5 steps not above `target` metres.
double niceLength(double target) {
  double best = 0.1;
  for (double decade = 0.1; decade <= 1e5; decade *= 10)
    for (double k : {1.0, 2.0, 5.0})
      if (k * decade <= target) best = k * decade;
  return best;
}

}  // namespace

namespace {
/** A pixel coordinate, clamped to +-2^24 (far outside any picture, so the
 *  drawing code clips it; the arithmetic on it cannot overflow). NaN gives
 *  the far negative edge: nothing is drawn there. */
int pixel(double v) {
  constexpr double kFar = 16777216.0;
  const double f = std::floor(v);
  if (!(f > -kFar)) return -static_cast<int>(kFar);
  if (f > kFar) return static_cast<int>(kFar);
  return static_cast<int>(f);
}
bool finitePoint(const mrpt::math::TPoint2D& p) { return std::isfinite(p.x) && std::isfinite(p.y); }
}  // namespace

int RenderGeometry::px(double x) const { return pixel((x - x_min) * pixels_per_metre); }
int RenderGeometry::py(double y) const { return pixel((y_max - y) * pixels_per_metre); }

namespace {

using Cell = COccupancyGridMap2D::cellType;
using UCell = COccupancyGridMap2D::cellTypeUnsigned;

/** One shade (class colour or grey level) per raw cell value. */
std::vector<uint8_t> shadeTable(const RenderOptions& o) {
  std::vector<uint8_t> shade(size_t{1} << (8 * sizeof(Cell)));
  for (size_t u = 0; u < shade.size(); ++u) {
    const float p = COccupancyGridMap2D::l2p(static_cast<Cell>(static_cast<UCell>(u)));
    if (o.grey_levels) {
      shade[u] = static_cast<uint8_t>(std::lround(std::clamp(p, 0.0f, 1.0f) * 255));
    } else {
      const CellClass k = classifyCell(p, o.thresholds);
      shade[u] = k == CellClass::Free ? kFree : k == CellClass::Occupied ? kOccupied : kUnknown;
    }
  }
  return shade;
}

/** The cells drawn: [x0, x1) x [y0, y1). */
struct CellBox {
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
};

/** All cells, or the known ones plus o.crop_margin_m. */
CellBox cellsShown(const COccupancyGridMap2D& map, const RenderOptions& o) {
  const int sx = static_cast<int>(map.getSizeX()), sy = static_cast<int>(map.getSizeY());
  CellBox b{0, sx, 0, sy};
  if (!o.crop_to_known) return b;
  const auto& raw = map.getRawMap();
  int ax0 = sx, ax1 = -1, ay0 = sy, ay1 = -1;
  for (int cy = 0; cy < sy; ++cy)
    for (int cx = 0; cx < sx; ++cx) {
      const Cell c =
          raw[static_cast<size_t>(cx) + static_cast<size_t>(cy) * static_cast<size_t>(sx)];
      if (classifyCell(COccupancyGridMap2D::l2p(c), o.thresholds) == CellClass::Unknown) continue;
      ax0 = std::min(ax0, cx);
      ax1 = std::max(ax1, cx);
      ay0 = std::min(ay0, cy);
      ay1 = std::max(ay1, cy);
    }
  if (ax1 < 0) return b;
  const int m = static_cast<int>(std::ceil(std::max(0.0, o.crop_margin_m) / map.getResolution()));
  return {std::max(0, ax0 - m), std::min(sx, ax1 + 1 + m), std::max(0, ay0 - m),
          std::min(sy, ay1 + 1 + m)};
}

/** The picture's size and scale. */
struct Layout {
  RenderGeometry g;
  double cell_px = 1;  ///< pixels per cell
};

/** Pixels per cell: at least the option, enough for min_width_px, at most max_side_px. */
Layout layoutFor(const COccupancyGridMap2D& map, const CellBox& b, const RenderOptions& o) {
  const int ncx = b.x1 - b.x0, ncy = b.y1 - b.y0;
  double s = std::max(1, o.pixels_per_cell);
  if (ncx * s < o.min_width_px) s = std::ceil(static_cast<double>(o.min_width_px) / ncx);
  const int max_side = std::max(64, o.max_side_px);
  if (std::max(ncx, ncy) * s > max_side) {
    s = std::floor(static_cast<double>(max_side) / std::max(ncx, ncy));
    if (s < 1) s = static_cast<double>(max_side) / std::max(ncx, ncy);  // shrink big maps
  }
  const double res = map.getResolution();
  RenderGeometry g;
  g.x_min = map.getXMin() + b.x0 * res;
  g.y_max = map.getYMin() + b.y1 * res;
  g.pixels_per_metre = s / res;
  g.width = std::max(1, static_cast<int>(std::floor(ncx * s)));
  g.height = std::max(1, static_cast<int>(std::floor(ncy * s)));
  return {g, s};
}

/** The cells of `b`, north up, at the scale of `g`. */
mrpt::img::CImage paintCells(const COccupancyGridMap2D& map, const CellBox& b, const Layout& l,
                             const std::vector<uint8_t>& shade) {
  const int w = l.g.width, h = l.g.height, sx = static_cast<int>(map.getSizeX());
  const double s = l.cell_px;
  const auto& raw = map.getRawMap();
  mrpt::img::CImage img(static_cast<unsigned>(w), static_cast<unsigned>(h), mrpt::img::CH_RGB);
  std::vector<int> col_cell(w);
  for (int u = 0; u < w; ++u) col_cell[u] = std::min(b.x1 - 1, b.x0 + static_cast<int>(u / s));
  for (int v = 0; v < h; ++v) {
    const int cy = std::max(b.y0, b.y1 - 1 - static_cast<int>(v / s));  // north up
    uint8_t* row = img.ptrLine<uint8_t>(static_cast<unsigned>(v));
    for (int u = 0; u < w; ++u) {
      const Cell c = raw[static_cast<size_t>(col_cell[u]) + static_cast<size_t>(cy) * sx];
      row[3 * u] = row[3 * u + 1] = row[3 * u + 2] = shade[static_cast<UCell>(c)];
    }
  }
  return img;
}

void drawOverlay(mrpt::img::CImage& img, const RenderGeometry& g, const Overlay& given) {
  // Points that are not numbers have no place on the picture.
  Overlay ov = given;
  ov.points.erase(std::remove_if(ov.points.begin(), ov.points.end(),
                                 [](const auto& p) { return !finitePoint(p); }),
                  ov.points.end());
  if (ov.points.empty()) return;
  const TColor c = toColor(ov.colour);
  const int th = std::max(1, ov.thickness);
  if (ov.points_only) {
    const int r = std::max(1, th);
    for (const auto& p : ov.points)
      img.filledRectangle(g.px(p.x) - r, g.py(p.y) - r, g.px(p.x) + r, g.py(p.y) + r, c);
  } else {
    for (size_t i = 1; i < ov.points.size(); ++i) {
      const auto& a = ov.points[i - 1];
      const auto& b = ov.points[i];
      img.line(g.px(a.x), g.py(a.y), g.px(b.x), g.py(b.y), c, static_cast<unsigned>(th));
    }
    if (ov.points.size() == 1)
      img.filledRectangle(g.px(ov.points[0].x) - th, g.py(ov.points[0].y) - th,
                          g.px(ov.points[0].x) + th, g.py(ov.points[0].y) + th, c);
  }
  if (ov.start_end_markers) {
    const auto& a = ov.points.front();
    const auto& b = ov.points.back();
    const int r = std::max(5, 2 * th + 2);
    img.drawCircle(g.px(a.x), g.py(a.y), r, TColor(0, 160, 0), 3);
    img.filledRectangle(g.px(b.x) - r + 1, g.py(b.y) - r + 1, g.px(b.x) + r - 1, g.py(b.y) + r - 1,
                        TColor(200, 0, 0));
    img.rectangle(g.px(b.x) - r, g.py(b.y) - r, g.px(b.x) + r, g.py(b.y) + r, TColor(0, 0, 0));
  }
  if (!ov.label.empty())
    label(img, g.px(ov.points.front().x) + 6, g.py(ov.points.front().y) - 18, ov.label, c);
}

void drawScaleBar(mrpt::img::CImage& img, const RenderGeometry& g, const RenderOptions& o) {
  const int w = g.width, h = g.height;
  const double width_m = w / g.pixels_per_metre;
  const double len = o.scale_bar_m > 0 ? o.scale_bar_m : niceLength(width_m / 5);
  const int len_px = static_cast<int>(std::lround(len * g.pixels_per_metre));
  if (len_px >= 4 && len_px < w - 20) {
    const int x0 = 12, y0 = h - 14;
    const std::string text = metresText(len);
    img.filledRectangle(x0 - 6, y0 - 26, x0 + std::max(len_px, 9 * int(text.size())) + 6, y0 + 8,
                        TColor(255, 255, 255));
    img.filledRectangle(x0, y0 - 2, x0 + len_px, y0 + 2, TColor(0, 0, 0));
    img.filledRectangle(x0, y0 - 8, x0 + 1, y0 + 2, TColor(0, 0, 0));
    img.filledRectangle(x0 + len_px - 1, y0 - 8, x0 + len_px, y0 + 2, TColor(0, 0, 0));
    img.textOut(x0, y0 - 24, text, TColor(0, 0, 0));
  }
}

}  // namespace

mrpt::img::CImage renderGridMap(const COccupancyGridMap2D& map, const RenderOptions& o,
                                RenderGeometry* geometry) {
  if (map.getSizeX() == 0 || map.getSizeY() == 0) throw InputError("the map has no cells to draw");
  const CellBox box = cellsShown(map, o);
  const Layout layout = layoutFor(map, box, o);
  const RenderGeometry& g = layout.g;
  mrpt::img::CImage img = paintCells(map, box, layout, shadeTable(o));
  for (const Overlay& ov : o.overlays) drawOverlay(img, g, ov);
  if (o.scale_bar && g.width >= 120 && g.height >= 60) drawScaleBar(img, g, o);
  if (!o.title.empty()) label(img, 8, 6, o.title, TColor(0, 0, 0));
  if (geometry) *geometry = g;
  return img;
}

void renderGridMapPng(const COccupancyGridMap2D& map, const std::string& path,
                      const RenderOptions& options) {
  map_detail::requireParentFolder(path);
  const mrpt::img::CImage img = renderGridMap(map, options);
  map_detail::TempFile tmp(path, ".png");
  bool ok = false;
  try {
    ok = img.saveToFile(tmp.path());
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok) throw std::runtime_error(path + ": cannot write the PNG");
  tmp.commit();
}

}  // namespace carenav::io
