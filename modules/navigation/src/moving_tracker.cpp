// Moving-obstacle tracks: nearest-neighbour association of clusters with a
// constant-velocity prediction (the people model of [Conceicao16, Sec. 6.1]'s
// person-crossing and person-towards tests: a person walks straight at a
// steady pace).
#include <carenav/navigation/moving_tracker.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace carenav::navigation {

std::vector<std::vector<size_t>> clusterPoints(const std::vector<TPoint2D>& pts, double link) {
  std::vector<std::vector<size_t>> out;
  std::vector<int> label(pts.size(), -1);
  const double l2 = link * link;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (label[i] >= 0) continue;
    label[i] = static_cast<int>(out.size());
    std::vector<size_t> members{i};
    for (size_t k = 0; k < members.size(); ++k) {
      const TPoint2D& a = pts[members[k]];
      for (size_t j = 0; j < pts.size(); ++j) {
        if (label[j] >= 0) continue;
        const double dx = pts[j].x - a.x, dy = pts[j].y - a.y;
        if (dx * dx + dy * dy <= l2) {
          label[j] = label[i];
          members.push_back(j);
        }
      }
    }
    out.push_back(std::move(members));
  }
  return out;
}

size_t distinctCells(const std::vector<TPoint2D>& pts, const std::vector<size_t>& idx,
                     double cell) {
  std::vector<std::pair<int64_t, int64_t>> cells;
  cells.reserve(idx.size());
  for (size_t i : idx)
    cells.emplace_back(static_cast<int64_t>(std::floor(pts[i].x / cell)),
                       static_cast<int64_t>(std::floor(pts[i].y / cell)));
  std::sort(cells.begin(), cells.end());
  return static_cast<size_t>(std::unique(cells.begin(), cells.end()) - cells.begin());
}

double travelled(const MovingTrack& k) {
  if (k.history.size() < 2) return 0;
  const TPoint2D &a = k.history.front().second, &b = k.history.back().second;
  return std::hypot(b.x - a.x, b.y - a.y);
}

void MovingTracker::update(const std::vector<TPoint2D>& moved_in, double t) {
  // drop tracks not seen for a while
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const MovingTrack& k) { return t - k.seen > p_.keep; }),
                tracks_.end());
  const auto clusters = clusterPoints(moved_in, p_.link);
  std::vector<MovingTrack> seen;
  std::vector<char> used(tracks_.size(), 0);
  bodies_.clear();
  for (const auto& c : clusters) {
    MovingTrack m;
    for (size_t i : c) m.centroid.x += moved_in[i].x, m.centroid.y += moved_in[i].y;
    m.centroid.x /= c.size();
    m.centroid.y /= c.size();
    for (size_t i : c)
      m.radius = std::max(m.radius,
                          std::hypot(moved_in[i].x - m.centroid.x, moved_in[i].y - m.centroid.y));
    if (m.radius > p_.max_radius) continue;  // not a person
    m.seen = t;
    m.sightings = 1;
    // The nearest track, by its constant-velocity prediction while fresh,
    // else by where it was last seen, the gate widening with the time unseen.
    size_t best = tracks_.size();
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < tracks_.size(); ++k) {
      if (used[k]) continue;
      const MovingTrack& o = tracks_[k];
      const double dt = t - o.seen;
      double d = std::hypot(m.centroid.x - o.centroid.x, m.centroid.y - o.centroid.y);
      if (dt <= p_.fresh)
        d = std::min(d, std::hypot(m.centroid.x - o.centroid.x - o.velocity.x * dt,
                                   m.centroid.y - o.centroid.y - o.velocity.y * dt));
      const double gate = p_.gate + (dt > p_.fresh ? p_.hidden_speed * (dt - p_.fresh) : 0.0);
      if (d < gate && d < best_d) best_d = d, best = k;
    }
    if (best == tracks_.size() &&
        distinctCells(moved_in, c, p_.cell) < static_cast<size_t>(p_.min_cells))
      continue;  // no body: an edge cell flickering, not a person stepping in
    for (size_t i : c) bodies_.push_back(moved_in[i]);
    if (best < tracks_.size()) {
      used[best] = 1;
      const MovingTrack& prev = tracks_[best];
      m.sightings = prev.sightings + 1;
      m.walked = prev.walked;
      if (t - prev.seen <= p_.fresh)  // a track back from hiding starts a new velocity
        for (const auto& h : prev.history)
          if (t - h.first <= p_.window) m.history.push_back(h);
    }
    m.history.push_back({t, m.centroid});
    m.velocity = {0, 0};
    if (m.history.size() >= 3) {
      // least-squares slope of x(t) and y(t)
      double st = 0, sx = 0, sy = 0;
      for (const auto& h : m.history) st += h.first, sx += h.second.x, sy += h.second.y;
      const double n = static_cast<double>(m.history.size());
      const double mt = st / n, mx = sx / n, my = sy / n;
      double stt = 0, stx = 0, sty = 0;
      for (const auto& h : m.history) {
        const double dt = h.first - mt;
        stt += dt * dt, stx += dt * (h.second.x - mx), sty += dt * (h.second.y - my);
      }
      if (stt > 1e-9) {
        TPoint2D v{stx / stt, sty / stt};
        const double s = std::hypot(v.x, v.y);
        if (s > p_.max_speed) v.x *= p_.max_speed / s, v.y *= p_.max_speed / s;
        m.velocity = v;
        if (std::hypot(v.x, v.y) >= p_.min_speed && travelled(m) >= p_.min_travel) m.walked = true;
      }
    }
    seen.push_back(m);
  }
  // tracks not seen this cycle stay (a person hidden for a moment)
  for (size_t k = 0; k < tracks_.size(); ++k)
    if (!used[k]) seen.push_back(tracks_[k]);
  tracks_ = std::move(seen);
  latest_ = t;
}

std::vector<TPoint2D> MovingTracker::hiddenRegions(double now, double step) const {
  std::vector<TPoint2D> out;
  if (!(step > 0)) return out;
  for (const auto& k : tracks_) {
    const double unseen = now - k.seen;
    if (!k.walked || unseen <= p_.fresh || unseen > p_.keep) continue;
    const double r = k.radius + std::min(p_.hidden_growth, p_.hidden_speed * (unseen - p_.fresh));
    const int n = static_cast<int>(std::ceil(r / step));
    for (int dy = -n; dy <= n; ++dy)
      for (int dx = -n; dx <= n; ++dx)
        if (std::hypot(dx, dy) * step <= r)
          out.push_back({k.centroid.x + dx * step, k.centroid.y + dy * step});
  }
  return out;
}

std::vector<TPoint2D> MovingTracker::predictedPath(double horizon, double step,
                                                   double widen) const {
  std::vector<TPoint2D> out;
  if (!(horizon > 0) || !(step > 0)) return out;
  for (const auto& k : tracks_) {
    if (k.history.size() < 3) continue;         // two displacements before a velocity is trusted
    if (k.seen < latest_ - p_.fresh) continue;  // out of sight: hiddenRegions
    const double s = std::hypot(k.velocity.x, k.velocity.y);
    if (s < p_.min_speed || travelled(k) < p_.min_travel) continue;
    const double len = s * horizon;
    const double ux = k.velocity.x / s, uy = k.velocity.y / s;
    const int n = static_cast<int>(std::ceil(len / step));
    for (int i = 1; i <= n; ++i) {
      const double d = std::min(len, i * step);
      // the body's spread across the direction of travel
      const double half = k.radius + widen;
      for (double off = -half; off <= half + 1e-9; off += step)
        out.push_back({k.centroid.x + ux * d - uy * off, k.centroid.y + uy * d + ux * off});
    }
  }
  return out;
}

}  // namespace carenav::navigation
