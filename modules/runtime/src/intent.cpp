// User intent sources for the live app (see intent.h).
#include <carenav/common/errors.h>
#include <carenav/common/file.h>
#include <carenav/common/text.h>
#include <carenav/runtime/intent.h>
#include <carenav/runtime/line_socket.h>

#include <fcntl.h>
#include <linux/joystick.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace carenav::navigation {

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

/** Splits a CSV line (double quotes protect commas). */
std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> f(1);
  bool q = false;
  for (char c : line) {
    if (c == '"')
      q = !q;
    else if (c == ',' && !q)
      f.emplace_back();
    else
      f.back() += c;
  }
  for (auto& s : f) s = trim(s);
  return f;
}

bool toNumber(const std::string& s, double& d) {
  const auto v = parseNumber(s);
  if (v) d = *v;
  return v.has_value();
}

// ---------------------------------------------------------------- script
class ScriptIntent : public IntentSource {
 public:
  ScriptIntent(std::string origin, std::vector<IntentRow> rows)
      : origin_(std::move(origin)), rows_(std::move(rows)) {}
  std::string describe() const override { return "csv:" + origin_; }
  std::optional<IntentSample> poll(double now) override {
    const IntentRow* r = nullptr;
    for (; next_ < rows_.size() && rows_[next_].t <= now + 1e-9; ++next_) {
    }
    if (next_ == 0) return std::nullopt;
    r = &rows_[next_ - 1];
    if (r->none) {
      if (!last_) return std::nullopt;
      return last_;  // silent: the last command, confirmed when it was heard
    }
    // A row holds until the next one; the last row only at its own time.
    const double confirmed = next_ < rows_.size() ? now : r->t;
    last_ = IntentSample{r->cmd, confirmed};
    return last_;
  }
  bool finished(double now) const override { return rows_.empty() || now > rows_.back().t; }

 private:
  std::string origin_;
  std::vector<IntentRow> rows_;
  size_t next_ = 0;
  std::optional<IntentSample> last_;
};

// ---------------------------------------------------------------- keyboard
class KeyboardIntent : public IntentSource {
 public:
  KeyboardIntent(const RobotParams& r, KeyboardSteps steps) : r_(r), steps_(steps) {
    if (!isatty(STDIN_FILENO))
      throw InputError("--intent keyboard: standard input is not a terminal");
    tcgetattr(STDIN_FILENO, &saved_);
    termios raw = saved_;
    raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);
    raw.c_cc[VMIN] = 0;
    raw.c_cc[VTIME] = 0;
    tcsetattr(STDIN_FILENO, TCSANOW, &raw);
  }
  ~KeyboardIntent() override { tcsetattr(STDIN_FILENO, TCSANOW, &saved_); }
  std::string describe() const override { return "keyboard"; }
  std::optional<IntentSample> poll(double now) override {
    char b[64];
    ssize_t n;
    while ((n = read(STDIN_FILENO, b, sizeof b)) > 0)
      for (ssize_t i = 0; i < n; ++i) key(b[i]);
    // A held command: the terminal is there, the user can change it any time.
    return IntentSample{cmd_, now};
  }
  bool finished(double) const override { return quit_; }

 private:
  void key(char c) {
    // Arrow keys arrive as ESC [ A/B/C/D.
    if (esc_ == 1) {
      esc_ = c == '[' ? 2 : 0;
      return;
    }
    if (esc_ == 2) {
      esc_ = 0;
      c = c == 'A' ? 'w' : c == 'B' ? 's' : c == 'C' ? 'd' : c == 'D' ? 'a' : 0;
    }
    switch (c) {
      case 27:
        esc_ = 1;
        break;
      case 'w':
        cmd_.v = std::min(r_.v_max, cmd_.v + steps_.dv);
        break;
      case 's':
        cmd_.v = std::max(r_.v_min, cmd_.v - steps_.dv);
        break;
      case 'a':
        cmd_.w = std::min(r_.w_max, cmd_.w + steps_.dw);
        break;
      case 'd':
        cmd_.w = std::max(-r_.w_max, cmd_.w - steps_.dw);
        break;
      case ' ':
        cmd_ = {};
        break;
      case 'q':
        quit_ = true;
        cmd_ = {};
        break;
      default:
        break;
    }
    if (std::abs(cmd_.v) < 1e-9) cmd_.v = 0;
    if (std::abs(cmd_.w) < 1e-9) cmd_.w = 0;
  }
  RobotParams r_;
  KeyboardSteps steps_;
  termios saved_{};
  Twist cmd_;
  int esc_ = 0;
  bool quit_ = false;
};

// ---------------------------------------------------------------- joystick
class JoystickIntent : public IntentSource {
 public:
  JoystickIntent(std::string dev, const RobotParams& r) : dev_(std::move(dev)), r_(r) {
    fd_ = open(dev_.c_str(), O_RDONLY | O_NONBLOCK);
    if (fd_ < 0) throw InputError(dev_ + ": cannot open the joystick: " + std::strerror(errno));
  }
  ~JoystickIntent() override {
    if (fd_ >= 0) close(fd_);
  }
  std::string describe() const override { return "joystick:" + dev_; }
  std::optional<IntentSample> poll(double now) override {
    if (fd_ < 0)
      return heard_ ? std::optional<IntentSample>(IntentSample{cmd_, lost_at_}) : std::nullopt;
    js_event e;
    for (;;) {
      const ssize_t n = read(fd_, &e, sizeof e);
      if (n == static_cast<ssize_t>(sizeof e)) {
        if ((e.type & ~JS_EVENT_INIT) == JS_EVENT_AXIS) {
          if (e.number == 1) fwd_ = e.value;
          if (e.number == 0) turn_ = e.value;
          heard_ = true;
        }
        continue;
      }
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) break;
      // Unplugged (ENODEV), end of a FIFO, or a short read: the user is gone.
      close(fd_);
      fd_ = -1;
      lost_at_ = now;
      break;
    }
    if (!heard_) return std::nullopt;
    cmd_ = joystickToTwist(fwd_, turn_, r_);
    return IntentSample{cmd_, fd_ >= 0 ? now : lost_at_};
  }
  bool finished(double) const override { return false; }

 private:
  std::string dev_;
  RobotParams r_;
  int fd_ = -1;
  int fwd_ = 0, turn_ = 0;
  bool heard_ = false;
  double lost_at_ = 0;
  Twist cmd_;
};

// ---------------------------------------------------------------- tcp
class TcpIntent : public IntentSource {
 public:
  TcpIntent(const std::string& host, int port, const RobotParams& r)
      : listener_(host, port), host_(host), r_(r) {}
  std::string describe() const override {
    return "tcp:" + host_ + ":" + std::to_string(listener_.port());
  }
  std::optional<IntentSample> poll(double now) override {
    if (!client_.open()) {
      client_ = listener_.accept(0);
      if (client_.open()) client_.sendLine("carenav intent: send lines 'v w' (m/s rad/s)");
    }
    std::vector<std::string> lines;
    if (client_.open()) {
      try {
        // A client that closes (or half-closes, or resets) is a user who
        // left: the source ends, the robot is stopped (finished()).
        if (!client_.readLines(lines, 0, 2 * client_.max_line)) dropped_ = true;
      } catch (const std::exception& e) {
        throw InputError(describe() + ": " + e.what());
      }
    }
    for (const auto& l : lines) {
      ++line_no_;
      const std::string s = trim(l);
      if (s.empty() || s[0] == '#') continue;
      std::istringstream in(s);
      double v, w;
      std::string extra;
      if (!(in >> v >> w) || (in >> extra) || !std::isfinite(v) || !std::isfinite(w))
        throw InputError(describe() + " line " + std::to_string(line_no_) + ": '" +
                         printableText(s, 80) + "' is not 'v w' (two numbers, m/s and rad/s)");
      last_ = IntentSample{{std::clamp(v, r_.v_min, r_.v_max), std::clamp(w, -r_.w_max, r_.w_max)},
                           now};
    }
    return last_;
  }
  bool finished(double) const override { return dropped_; }

 private:
  bool dropped_ = false;
  TcpListener listener_;
  std::string host_;
  RobotParams r_;
  LineSocket client_;
  size_t line_no_ = 0;
  std::optional<IntentSample> last_;
};

}  // namespace

Twist joystickToTwist(int axis_forward, int axis_turn, const RobotParams& r) {
  const double f = std::clamp(-axis_forward / 32767.0, -1.0, 1.0);
  const double t = std::clamp(-axis_turn / 32767.0, -1.0, 1.0);
  Twist c;
  c.v = f >= 0 ? f * r.v_max : -f * r.v_min;
  c.w = t * r.w_max;
  return c;
}

std::vector<IntentRow> parseIntentScript(const std::string& text, const std::string& origin) {
  std::istringstream in(text);
  std::string line;
  size_t ln = 0;
  int ct = 0, cv = 1, cw = 2;
  bool header_seen = false;
  std::vector<IntentRow> rows;
  auto fail = [&](const std::string& what) {
    throw InputError(origin + ":" + std::to_string(ln) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++ln;
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    const auto f = splitCsv(s);
    double d;
    if (!header_seen && rows.empty() && !toNumber(f[0], d)) {
      // A header: t,v,w or a navigation log's t,...,user_v,user_w,...
      header_seen = true;
      ct = cv = cw = -1;
      for (size_t i = 0; i < f.size(); ++i) {
        if (f[i] == "t") ct = static_cast<int>(i);
        if (f[i] == "v" || f[i] == "user_v") cv = static_cast<int>(i);
        if (f[i] == "w" || f[i] == "user_w") cw = static_cast<int>(i);
      }
      if (ct < 0 || cv < 0 || cw < 0)
        fail("header '" + s + "' names no t, v and w (or user_v, user_w) columns");
      continue;
    }
    const int need = std::max({ct, cv, cw}) + 1;
    if (static_cast<int>(f.size()) < need)
      fail(std::to_string(f.size()) + " fields, expected at least " + std::to_string(need) +
           " (a truncated row?)");
    if (!header_seen && f.size() != 3)
      fail("expected 't,v,w', got " + std::to_string(f.size()) + " fields");
    IntentRow r;
    if (!toNumber(f[ct], r.t)) fail("time '" + f[ct] + "' is not a finite number");
    if (f[cv].empty() && f[cw].empty()) {
      r.none = true;  // a navigation log's cycle without a user command
    } else {
      if (!toNumber(f[cv], r.cmd.v)) fail("v '" + f[cv] + "' is not a finite number");
      if (!toNumber(f[cw], r.cmd.w)) fail("w '" + f[cw] + "' is not a finite number");
    }
    if (!rows.empty() && r.t < rows.back().t)
      fail("time " + f[ct] + " is before the previous row's");
    rows.push_back(r);
  }
  if (rows.empty())
    throw InputError(origin + ": no commands (expected rows 't,v,w' or a navigation log)");
  return rows;
}

std::vector<IntentRow> readIntentScript(const std::string& path) {
  const std::string unreadable = "cannot open the intent script";
  const std::string text =
      readWholeFile(path, {unreadable, unreadable, unreadable, "an intent script"});
  if (text.find('\0') != std::string::npos)
    throw InputError(path + ": not a text file (an intent script is CSV 't,v,w')");
  return parseIntentScript(text, path);
}

std::unique_ptr<IntentSource> makeIntentSource(const std::string& spec, const RobotParams& robot) {
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "csv") {
    if (arg.empty()) throw InputError("--intent csv:FILE: no file given");
    return std::make_unique<ScriptIntent>(arg, readIntentScript(arg));
  }
  if (kind == "keyboard") return std::make_unique<KeyboardIntent>(robot, KeyboardSteps{});
  if (kind == "joystick")
    return std::make_unique<JoystickIntent>(arg.empty() ? "/dev/input/js0" : arg, robot);
  if (kind == "tcp") {
    std::pair<std::string, int> hp;
    try {
      hp = parseHostPort(arg, "127.0.0.1");
    } catch (const std::exception& e) {
      throw InputError("--intent tcp:" + arg + ": " + e.what());
    }
    try {
      return std::make_unique<TcpIntent>(hp.first, hp.second, robot);
    } catch (const std::runtime_error& e) {
      throw InputError(std::string("--intent tcp: ") + e.what());
    }
  }
  throw InputError("--intent '" + spec +
                   "': unknown source (csv:FILE, keyboard, joystick[:DEV], tcp:[HOST:]PORT)");
}

}  // namespace carenav::navigation
