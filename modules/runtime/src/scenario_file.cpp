// Reading scenario files (docs/navigate.md).
#include <carenav/common/errors.h>
#include <carenav/common/file.h>
#include <carenav/common/text.h>
#include <carenav/common/yaml.h>
#include <carenav/navigation/local_planner.h>
#include <carenav/runtime/scenario.h>

#include <mrpt/core/bits_math.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace carenav::navigation {

namespace fs = std::filesystem;
using yaml::Node;

std::optional<TPose2D> parseGoalText(const std::string& text) {
  double x, y, deg = 0;
  char c1, c2, extra;
  std::istringstream in(text);
  if (!(in >> x >> c1 >> y) || c1 != ',' || !std::isfinite(x) || !std::isfinite(y))
    return std::nullopt;
  if (!(in >> c2)) return TPose2D{x, y, kAnyHeading};  // "x,y": any heading
  if (c2 == ',' && (in >> deg) && !(in >> extra) && std::isfinite(deg))
    return TPose2D{x, y, mrpt::DEG2RAD(deg)};
  return std::nullopt;
}

std::optional<TPose2D> parsePoseText(const std::string& text) {
  const auto p = parseGoalText(text);
  if (p && std::isnan(p->phi)) return std::nullopt;  // a pose needs its heading
  return p;
}

std::optional<std::pair<double, double>> Scenario::userAt(double t, double yaw) const {
  const IntentEntry* e = nullptr;
  for (const auto& i : intent)
    if (i.t <= t + 1e-9) e = &i;
  if (!e) return std::nullopt;
  if (!e->heading) return std::make_pair(e->v, e->w);
  const double err = std::atan2(std::sin(*e->heading - yaw), std::cos(*e->heading - yaw));
  return std::make_pair(e->v, heading_gain * err);
}

namespace {

struct Reader {
  std::string origin;
  [[noreturn]] void fail(const Node& n, const std::string& what) const {
    throw InputError(origin + ":" + std::to_string(n.line) + ": " + what);
  }
  double number(const Node& n, const std::string& what) const {
    if (n.kind != Node::Kind::Scalar || n.quoted) fail(n, what + ": expected a number");
    const auto d = parseNumber(n.scalar);
    if (!d) fail(n, what + ": '" + n.scalar + "' is not a finite number");
    return *d;
  }
  std::string text(const Node& n, const std::string& what) const {
    if (n.kind != Node::Kind::Scalar || n.scalar.empty()) fail(n, what + ": expected text");
    return n.scalar;
  }
  std::vector<double> numbers(const Node& n, const std::string& what, size_t count) const {
    if (n.kind != Node::Kind::Seq || n.seq.size() != count)
      fail(n, what + ": expected [" + std::to_string(count) + " numbers]");
    std::vector<double> out;
    for (const auto& e : n.seq) out.push_back(number(e, what));
    return out;
  }
  TPose2D pose(const Node& n, const std::string& what) const {
    const auto v = numbers(n, what + " [x, y, heading_deg]", 3);
    return {v[0], v[1], mrpt::DEG2RAD(v[2])};
  }
  /** A goal: [x, y] (any heading), [x, y, heading_deg], or the name of a
   *  place or room. */
  GoalRef goal(const Node& n, const std::string& what) const {
    GoalRef g;
    if (n.kind == Node::Kind::Scalar && (n.quoted || !n.scalar.empty())) {
      g.name = text(n, what);
    } else if (n.kind == Node::Kind::Seq && n.seq.size() == 2) {
      const auto v = numbers(n, what + " [x, y]", 2);
      g.pose = TPose2D{v[0], v[1], kAnyHeading};
    } else {
      g.pose = pose(n, what + " [x, y] or");
    }
    return g;
  }
};

/** At most this many goals in a patrol (a bound on the reader's work). */
constexpr size_t kMaxPatrolGoals = 1000;

}  // namespace

Scenario parseScenario(const std::string& text, const std::string& origin,
                       const std::string& base_dir) {
  const Reader r{origin};
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw InputError(origin + ": empty scenario file");
  const Node root = yaml::parse(text, origin);
  if (root.kind != Node::Kind::Map) r.fail(root, "a scenario is a map of keys");
  static const std::set<std::string> known = {
      "format", "name",           "world",        "profile",  "plugin", "start",      "goal",
      "intent", "intent_heading", "heading_gain", "duration", "reach",  "forbidden",  "path_exists",
      "seed",   "places",         "user_speed",   "end",      "patrol", "leg_timeout"};
  for (size_t i = 0; i < root.map.size(); ++i)
    if (!known.count(root.map[i].first))
      throw InputError(origin + ":" + std::to_string(root.key_lines[i]) + ": unknown key '" +
                       root.map[i].first + "'");
  const Node* fmt = root.find("format");
  if (!fmt) throw InputError(origin + ": no 'format: 1' line: not a carenav scenario");
  if (r.number(*fmt, "format") != 1)
    r.fail(*fmt, "format " + fmt->scalar + " is not supported (1 is)");
  // The last line is `end: true`, so a file cut short is noticed.
  const Node* end = root.find("end");
  if (!end || end->scalar != "true")
    throw InputError(origin + ": no final 'end: true': the file is truncated");

  Scenario s;
  s.file = origin;
  s.name = fs::path(origin).stem().string();
  auto resolve = [&](const std::string& p) {
    return fs::path(p).is_absolute() ? p : (fs::path(base_dir) / p).lexically_normal().string();
  };
  if (const Node* n = root.find("name")) s.name = r.text(*n, "name");
  const Node* world = root.find("world");
  if (!world) throw InputError(origin + ": 'world:' (a simulator world file) is required");
  s.world = resolve(r.text(*world, "world"));
  if (const Node* n = root.find("profile")) s.profile = resolve(r.text(*n, "profile"));
  if (const Node* n = root.find("plugin")) s.plugin = r.text(*n, "plugin");
  if (const Node* n = root.find("places")) s.places = resolve(r.text(*n, "places"));
  const Node* start = root.find("start");
  if (!start) throw InputError(origin + ": 'start: [x, y, heading_deg]' is required");
  s.start = r.pose(*start, "start");
  if (const Node* n = root.find("goal")) {
    const GoalRef g = r.goal(*n, "goal");
    s.goal = g.pose;
    s.goal_name = g.name;
  }
  if (const Node* n = root.find("patrol")) {
    if (root.find("goal")) r.fail(*n, "give either goal or patrol, not both");
    if (n->kind != Node::Kind::Seq || n->seq.size() < 2 || n->seq.size() > kMaxPatrolGoals)
      r.fail(*n, "patrol: expected a list of 2 to " + std::to_string(kMaxPatrolGoals) +
                     " goals ([x, y, heading_deg] or a place name)");
    for (const auto& e : n->seq) s.patrol.push_back(r.goal(e, "patrol goal"));
    s.goal = s.patrol.front().pose;
    s.goal_name = s.patrol.front().name;
  }
  if (const Node* n = root.find("leg_timeout")) {
    s.leg_timeout = r.number(*n, "leg_timeout");
    if (s.leg_timeout <= 0) r.fail(*n, "leg_timeout must be positive (s)");
  }
  auto readIntent = [&](const Node& n, bool heading) {
    if (n.kind != Node::Kind::Seq || n.seq.empty())
      r.fail(n, "intent: expected a list of [t, v, w] (intent_heading: [t, v, heading_deg])");
    double last_t = -1;
    for (const auto& e : n.seq) {
      const auto v = r.numbers(e, heading ? "intent_heading entry" : "intent entry", 3);
      if (v[0] < 0 || v[0] <= last_t) r.fail(e, "intent times must increase from 0");
      last_t = v[0];
      IntentEntry ie;
      ie.t = v[0];
      ie.v = v[1];
      if (heading)
        ie.heading = mrpt::DEG2RAD(v[2]);
      else
        ie.w = v[2];
      s.intent.push_back(ie);
    }
  };
  const Node* intent = root.find("intent");
  const Node* intent_h = root.find("intent_heading");
  if (intent && intent_h) r.fail(*intent_h, "give either intent or intent_heading, not both");
  if (intent) readIntent(*intent, false);
  if (intent_h) readIntent(*intent_h, true);
  const bool has_goal = s.goal.has_value() || !s.goal_name.empty();
  if (has_goal == !s.intent.empty())
    throw InputError(origin +
                     ": give exactly one of 'goal' or 'patrol' (goal navigation) and "
                     "'intent'/'intent_heading' (a user pushing a walker)");
  if (const Node* n = root.find("heading_gain")) s.heading_gain = r.number(*n, "heading_gain");
  if (const Node* n = root.find("user_speed")) {
    s.user_speed = r.number(*n, "user_speed");
    if (s.user_speed <= 0 || s.user_speed > 2) r.fail(*n, "user_speed must be in (0, 2] m/s");
  }
  if (const Node* n = root.find("duration")) {
    s.duration = r.number(*n, "duration");
    if (s.duration <= 0 || s.duration > 3600) r.fail(*n, "duration must be in (0, 3600] s");
  }
  if (const Node* n = root.find("reach")) {
    const auto v = r.numbers(*n, "reach [x, y, radius]", 3);
    if (v[2] <= 0) r.fail(*n, "reach: the radius must be positive");
    s.reach = std::make_pair(TPoint2D{v[0], v[1]}, v[2]);
  }
  if (const Node* n = root.find("forbidden")) {
    if (n->kind != Node::Kind::Seq) r.fail(*n, "forbidden: expected a list of polygons");
    for (const auto& poly : n->seq) {
      if (poly.kind != Node::Kind::Seq || poly.seq.size() < 3)
        r.fail(poly, "forbidden: a polygon is a list of at least 3 [x, y] corners");
      std::vector<TPoint2D> pts;
      for (const auto& c : poly.seq) {
        const auto v = r.numbers(c, "forbidden corner [x, y]", 2);
        pts.push_back({v[0], v[1]});
      }
      s.forbidden.push_back(pts);
    }
  }
  if (const Node* n = root.find("path_exists")) {
    if (n->scalar != "true" && n->scalar != "false") r.fail(*n, "path_exists: true or false");
    s.path_exists = n->scalar == "true";
  }
  if (const Node* n = root.find("seed")) s.seed = static_cast<int>(r.number(*n, "seed"));
  return s;
}

Scenario readScenario(const std::string& path) {
  const std::string unreadable = "cannot open the scenario file";
  const std::string text =
      readWholeFile(path, {unreadable, unreadable, unreadable, "a scenario file"});
  return parseScenario(text, path, fs::path(path).parent_path().string());
}

}  // namespace carenav::navigation
