// Where a walker's user intent comes from in the live app (`carenav
// navigate --intent SRC`): a CSV script of timed (v, w) commands (also a
// navigation log, to replay a run), the terminal's keyboard, a Linux
// joystick device, or a TCP port. Every source says when it last heard from
// the user, so the safety supervisor stops the walker when the user falls
// silent (intent_timeout).
#pragma once

#include <carenav/common/robot.h>
#include <carenav/navigation/local_planner.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace carenav::navigation {

/** The user's command and when it was last confirmed (s, the run's clock). */
struct IntentSample {
  Twist cmd;
  double t = 0;
};

class IntentSource {
 public:
  virtual ~IntentSource() = default;
  /** For the status line and errors: "csv:FILE", "keyboard", ... */
  virtual std::string describe() const = 0;
  /** The user's command at time `now` of the run; nullopt while there is
   *  none yet. Throws InputError when the source sends a malformed message. */
  virtual std::optional<IntentSample> poll(double now) = 0;
  /** True once the source has no more to say (a script past its last row,
   *  the user pressed q). */
  virtual bool finished(double now) const = 0;
};

/** One row of an intent script: from time t on, (v, w); `none` rows (a
 *  navigation log's cycles without a user command) mean the user is silent. */
struct IntentRow {
  double t = 0;
  Twist cmd;
  bool none = false;
};

/** Reads an intent script. Either rows "t,v,w" (an optional header naming
 *  the columns t,v,w; '#' comments), or a navigation log of `carenav
 *  navigate` (columns t, user_v, user_w; the rest ignored) to replay the
 *  user of a run. Times must not decrease. Throws InputError "FILE:LINE:
 *  what" for an empty or malformed file. */
std::vector<IntentRow> readIntentScript(const std::string& path);
std::vector<IntentRow> parseIntentScript(const std::string& text, const std::string& origin);

/** Keyboard steps: each key press changes the command by these. */
struct KeyboardSteps {
  double dv = 0.05;  ///< m/s per press of w / s / arrow up / arrow down
  double dw = 0.1;   ///< rad/s per press of a / d / arrow left / arrow right
};

/** The sources by spec:
 *  - "csv:FILE"        a script (readIntentScript); held row by row, the
 *                      last row's command until its time, then silent;
 *  - "keyboard"        the terminal (w/s faster/slower, a/d turn, arrows,
 *                      space stop, q quit); needs a terminal on stdin;
 *  - "joystick[:DEV]"  a Linux joystick (default /dev/input/js0): axis 1
 *                      forward/back to v (full deflection = the robot's
 *                      limits), axis 0 left/right to w; silent when the
 *                      device goes away;
 *  - "tcp:PORT" or "tcp:HOST:PORT"  listens (default host 127.0.0.1) for
 *                      one client sending lines "v w"; each line confirms
 *                      the command, so a client that stops sending goes
 *                      stale.
 *  Throws InputError for an unknown spec or a source that cannot open. */
std::unique_ptr<IntentSource> makeIntentSource(const std::string& spec, const RobotParams& robot);

/** Joystick axis value (-32767..32767) to a command within the robot's
 *  limits: pushing forward (negative axis 1) drives forward. */
Twist joystickToTwist(int axis_forward, int axis_turn, const RobotParams& robot);

}  // namespace carenav::navigation
