// SPDX-License-Identifier: MIT
// The G-code interpreter: lines of words (gcode_lines.h) as the curves the
// pen draws. The meaning of the codes follows LinuxCNC's G-code reference,
// Marlin's G-code documentation (G5, M280, checksums) and Grbl's wiki
// (docs/formats.md, "G-code", names what is taken from where).
#include "fdsurf/host/gcode_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>

#include "fdsurf/host/conic_arc.h"
#include "fdsurf/host/text.h"
#include "gcode_lines.h"

namespace fdsurf::host {
namespace {

using gcode::Line;
using gcode::Word;

constexpr double kPi = std::numbers::pi;

// A G or M code in tenths: G5.1 is 51, G38.2 is 382.
int Tenths(double value) { return static_cast<int>(std::lround(value * 10)); }

std::string CodeName(char letter, int tenths) {
  std::string text = std::string(1, letter) + std::to_string(tenths / 10);
  if (tenths % 10 != 0) text += "." + std::to_string(tenths % 10);
  return text;
}

// Why a G code that moves in a way the reader does not follow is refused,
// or "" when it is not one of those.
std::string RefusedGReason(int g) {
  if (g == 330 || g == 331 || g == 760) return "threading is not supported";
  if (g >= 382 && g <= 385) return "probing is not supported";
  if (g == 730 || (g >= 810 && g <= 890)) return "canned cycles are not supported";
  if (g == 410 || g == 420 || g == 411 || g == 421) return "cutter compensation is not supported";
  if (g == 430 || g == 431 || g == 432) return "tool length offsets are not supported";
  if ((g >= 550 && g <= 593) || g == 100) {
    return "only one coordinate system (G54) is supported";
  }
  if (g == 530) return "machine-coordinate moves are not supported";
  if (g == 70) return "lathe diameter mode is not supported";
  if (g == 290) return "bed probing is not supported";
  return "";
}

// Why a harmless G code is ignored, or "" when it is not one of those.
std::string IgnoredGReason(int g) {
  switch (g) {
    case 80:
      return "lathe radius mode is the default";
    case 400:
      return "cutter compensation is off already";
    case 490:
      return "no tool length offset is in use";
    case 540:
      return "G54 is the only coordinate system";
    case 610:
    case 611:
    case 640:
      return "path blending does not change the drawing";
    case 800:
      return "no canned cycle is in use";
    case 930:
    case 940:
    case 950:
      return "feed modes do not change the drawing";
    case 980:
    case 990:
      return "canned-cycle return modes do not change the drawing";
    default:
      return "";
  }
}

// The words of one line, sorted for the interpreter.
struct Block {
  int line = 0;
  std::vector<int> g;          // tenths
  std::vector<int> m;          // tenths
  std::map<char, Word> words;  // every other letter, at most once

  [[nodiscard]] bool Has(char letter) const { return words.count(letter) != 0; }
  [[nodiscard]] std::optional<double> Get(char letter) const {
    const auto it = words.find(letter);
    if (it == words.end()) return std::nullopt;
    return it->second.value;
  }
};

// The plane's axes: `a` and `b` (counter-clockwise turns from a to b, seen
// from the positive side of the normal `n`, as LinuxCNC defines G18: Z then
// X), and their offset letters.
struct PlaneAxes {
  std::size_t a, b, n;
  char offset_a, offset_b;
  const char* name;
};

PlaneAxes AxesOf(int plane) {
  if (plane == 18) return {2, 0, 1, 'K', 'I', "G18 (ZX)"};
  if (plane == 19) return {1, 2, 0, 'J', 'K', "G19 (YZ)"};
  return {0, 1, 2, 'I', 'J', "G17 (XY)"};
}

class Interpreter {
 public:
  Interpreter(std::string name, const GcodeReadOptions& options)
      : name_(std::move(name)), options_(options) {}

  void Run(const std::vector<Line>& lines);
  PatchSet Finish();

 private:
  using Axes = std::array<std::optional<double>, 3>;

  [[nodiscard]] InputError Error(int line, const std::string& what) const {
    return InputError(name_ + ":" + std::to_string(line) + ": " + what);
  }
  void Note(const std::string& key, int line, const std::string& what);

  [[nodiscard]] Block Sort(const Line& line) const;
  void ScanPenMechanisms(const std::vector<Line>& lines);
  bool Execute(const Block& block);  // false at M2/M30
  void SetModes(const Block& block);
  void PenCommands(const Block& block);
  void AxisCommand(const Block& block);
  void CheckLeftoverWords(const Block& block, int motion) const;

  double Length(double value, int line);
  Axes AxisWords(const Block& block);
  [[nodiscard]] Point3 Target(const Axes& axes) const;
  [[nodiscard]] bool PenDownAt(const Point3& machine, bool z_known) const;

  void Move(const Block& block, int motion, const Point3& target, bool z_known_after);
  void Arc(const Block& block, bool clockwise, const Point3& target, bool drawn);
  void AddArcPieces(int line, const std::string& code, const PlaneAxes& p,
                    const std::array<double, 2>& centre, double radius, double start, double sweep,
                    const Point3& target);
  void Cubic(const Block& block, const Point3& target, bool drawn);
  void Quadratic(const Block& block, const Point3& target, bool drawn);
  void AddCurve(const std::array<Point3, 4>& g, int line, const std::string& code, bool straight);
  void NewLayer(const std::string& name);

  std::string name_;
  GcodeReadOptions options_;
  PatchSet set_;
  std::set<std::string> noted_;

  // Where the machine is, in the program's unit, from where it started.
  Point3 position_{0, 0, 0};
  // Work coordinates = machine − offset (G92).
  Point3 offset_{0, 0, 0};
  bool z_known_ = false;
  bool absolute_ = true;
  bool arc_centre_absolute_ = false;
  int plane_ = 17;
  int motion_ = 0;  // tenths: 0, 10, 20, 30, 50, 51
  std::string unit_;
  double scale_ = 1;  // program values × scale_ = the first unit's values

  // Pen mechanisms the program uses, and their state.
  bool uses_spindle_ = false;
  bool uses_servo_ = false;
  bool uses_z_ = false;
  bool spindle_on_ = false;
  bool servo_down_ = false;

  // The previous motion was a G5 whose second control point was this far
  // from its end (P, Q in the first unit): a G5 without I J continues it.
  std::optional<std::array<double, 2>> previous_g5_pq_;
  bool drawn_helix_noted_ = false;

  std::vector<std::string> layer_names_{"start"};
  int layer_ = 0;
};

void Interpreter::Note(const std::string& key, int line, const std::string& what) {
  if (!noted_.insert(key).second) return;
  set_.notes.push_back(name_ + ":" + std::to_string(line) + ": " + what);
}

Block Interpreter::Sort(const Line& line) const {
  Block block;
  block.line = line.number;
  for (const Word& word : line.words) {
    if (word.letter == 'G' || word.letter == 'M') {
      if (word.value < 0) throw Error(line.number, "word '" + word.text + "': not a code");
      (word.letter == 'G' ? block.g : block.m).push_back(Tenths(word.value));
      continue;
    }
    if (!block.words.emplace(word.letter, word).second) {
      throw Error(line.number, std::string("word '") + word.letter + "' given twice");
    }
  }
  return block;
}

void Interpreter::ScanPenMechanisms(const std::vector<Line>& lines) {
  for (const Line& line : lines) {
    if (line.block_delete && options_.skip_block_delete) continue;
    for (const Word& word : line.words) {
      if (word.letter == 'M') {
        const int m = Tenths(word.value);
        if (m == 30 || m == 40 || m == 50) uses_spindle_ = true;
        if (m == 2800) uses_servo_ = true;
      }
      if (word.letter == 'Z') uses_z_ = true;
    }
  }
}

void Interpreter::Run(const std::vector<Line>& lines) {
  ScanPenMechanisms(lines);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const Line& line = lines[i];
    if (line.block_delete && options_.skip_block_delete) {
      Note("/", line.number, "lines starting with '/' (block delete) are skipped");
      continue;
    }
    if (!Execute(Sort(line)) && i + 1 < lines.size()) {
      Note("end", line.number,
           "the program ends here; the " + std::to_string(lines.size() - i - 1) +
               " lines with words after it are not read");
      return;
    }
  }
}

double Interpreter::Length(double value, int line) {
  if (unit_.empty()) {
    unit_ = "mm";
    Note("unit", line, "no G20/G21 before the first coordinate: millimetres assumed");
  }
  return value * scale_;
}

void Interpreter::SetModes(const Block& block) {
  for (const int g : block.g) {
    if (g == 200 || g == 210) {
      const std::string unit = g == 200 ? "in" : "mm";
      if (unit_.empty()) {
        unit_ = unit;
      } else if (unit != unit_) {
        scale_ = g == 200 ? 25.4 : 1 / 25.4;
        Note("mixed units", block.line,
             CodeName('G', g) + ": the values that follow are converted to " + unit_ +
                 ", the program's first unit");
      } else {
        scale_ = 1;
      }
    } else if (g == 170 || g == 180 || g == 190) {
      plane_ = g / 10;
    } else if (g == 900 || g == 910) {
      absolute_ = g == 900;
    } else if (g == 901 || g == 911) {
      arc_centre_absolute_ = g == 901;
    }
  }
}

// M codes: the pen, tool changes and pauses (pauses and ends are taken after
// the line's motion, in Execute).
void Interpreter::PenCommands(const Block& block) {
  for (const int m : block.m) {
    switch (m) {
      case 30:
      case 40:
        spindle_on_ = true;
        break;
      case 50:
        spindle_on_ = false;
        break;
      case 2800: {
        const std::optional<double> angle = block.Get('S');
        if (!angle) throw Error(block.line, "M280: no S (servo angle)");
        servo_down_ = *angle < options_.servo_down_below;
        Note("M280", block.line,
             "M280: the pen is down while the servo angle is below " +
                 FormatNumber(options_.servo_down_below) + " degrees");
        break;
      }
      case 60: {
        const std::optional<double> tool = block.Get('T');
        NewLayer(tool ? "T" + FormatNumber(*tool)
                      : "tool change at line " + std::to_string(block.line));
        break;
      }
      case 0:
      case 10:
      case 20:
      case 300:
        break;
      case 980:
      case 990:
        throw Error(block.line, CodeName('M', m) + ": subprograms are not supported");
      default:
        Note(CodeName('M', m), block.line,
             CodeName('M', m) + " ignored (it does not move the pen)");
    }
  }
  if (block.Has('T') && std::find(block.m.begin(), block.m.end(), 60) == block.m.end()) {
    Note("T", block.line, "T without M6 ignored (only a tool change, T<n> M6, starts a layer)");
  }
}

bool Interpreter::Execute(const Block& block) {
  int motion_on_line = -1;
  int axis_command = -1;  // G92 or G28
  for (const int g : block.g) {
    if (g == 0 || g == 10 || g == 20 || g == 30 || g == 50 || g == 51) {
      if (motion_on_line >= 0) {
        throw Error(block.line, "two motion codes, " + CodeName('G', motion_on_line) + " and " +
                                    CodeName('G', g) + ", on one line");
      }
      motion_on_line = g;
    } else if (g == 920 || g == 280) {
      axis_command = g;
    } else if (g == 40 || g == 200 || g == 210 || g == 170 || g == 180 || g == 190 || g == 900 ||
               g == 910 || g == 901 || g == 911) {
      // Dwell (nothing to draw), or a mode that SetModes takes.
    } else if (const std::string refused = RefusedGReason(g); !refused.empty()) {
      throw Error(block.line, CodeName('G', g) + ": " + refused);
    } else if (const std::string ignored = IgnoredGReason(g); !ignored.empty()) {
      Note(CodeName('G', g), block.line, CodeName('G', g) + " ignored (" + ignored + ")");
    } else {
      throw Error(block.line, CodeName('G', g) + ": not supported (an unknown G code may move)");
    }
  }
  for (const char axis : {'A', 'B', 'C', 'U', 'V', 'W'}) {
    if (block.Has(axis)) {
      throw Error(block.line,
                  std::string("word '") + axis + "': only the X, Y and Z axes are supported");
    }
  }
  if (block.Has('E')) Note("E", block.line, "E (extrusion) words ignored");
  SetModes(block);
  PenCommands(block);
  if (motion_on_line >= 0) motion_ = motion_on_line;
  if (axis_command >= 0 && motion_on_line >= 0) {
    throw Error(block.line, CodeName('G', axis_command) + " and " + CodeName('G', motion_on_line) +
                                " on one line");
  }
  if (axis_command >= 0) {
    AxisCommand(block);
    CheckLeftoverWords(block, -1);
  } else {
    const bool has_axes = block.Has('X') || block.Has('Y') || block.Has('Z');
    const bool arc_words = block.Has('I') || block.Has('J') || block.Has('K') || block.Has('R');
    const bool curve_motion = motion_ == 20 || motion_ == 30 || motion_ == 50 || motion_ == 51;
    if (has_axes || (curve_motion && (motion_on_line >= 0 || arc_words))) {
      const Axes axes = AxisWords(block);
      const Point3 target = Target(axes);
      Move(block, motion_, target, z_known_ || axes[2].has_value());
      CheckLeftoverWords(block, motion_);
    } else {
      CheckLeftoverWords(block, -1);
    }
  }
  for (const int m : block.m) {
    if (m == 0 || m == 10) {
      NewLayer("after " + CodeName('M', m) + " at line " + std::to_string(block.line));
    }
    if (m == 20 || m == 300) return false;
  }
  return true;
}

// Words that only a motion uses, on a line where no motion took them.
void Interpreter::CheckLeftoverWords(const Block& block, int motion) const {
  const bool arc = motion == 20 || motion == 30;
  const bool spline = motion == 50 || motion == 51;
  for (const char letter : {'I', 'J', 'K', 'R', 'Q'}) {
    if (!block.Has(letter)) continue;
    const bool used = (arc && letter != 'Q') || (spline && letter != 'K' && letter != 'R');
    if (!used) {
      throw Error(block.line, std::string("word '") + letter +
                                  "': no G2, G3, G5 or G5.1 on the line to use it");
    }
  }
}

Interpreter::Axes Interpreter::AxisWords(const Block& block) {
  Axes axes;
  const char letters[3] = {'X', 'Y', 'Z'};
  for (int c = 0; c < 3; ++c) {
    if (const auto value = block.Get(letters[c])) axes[c] = Length(*value, block.line);
  }
  return axes;
}

Point3 Interpreter::Target(const Axes& axes) const {
  Point3 target = position_;
  for (std::size_t c = 0; c < 3; ++c) {
    if (!axes[c]) continue;
    target[c] = absolute_ ? *axes[c] + offset_[c] : position_[c] + *axes[c];
  }
  return target;
}

// G92 (the current point gets the given work coordinates) and G28 (travel
// home, through the given point: home is where the program started).
void Interpreter::AxisCommand(const Block& block) {
  const Axes axes = AxisWords(block);
  previous_g5_pq_.reset();
  if (std::find(block.g.begin(), block.g.end(), 920) != block.g.end()) {
    for (std::size_t c = 0; c < 3; ++c) {
      if (axes[c]) offset_[c] = position_[c] - *axes[c];
    }
    if (axes[2]) z_known_ = true;
    return;
  }
  Note("G28", block.line,
       "G28: home is taken as where the program started (0, 0, 0); " +
           std::string("the move there is travel"));
  position_ = {0, 0, 0};
  z_known_ = true;
}

bool Interpreter::PenDownAt(const Point3& machine, bool z_known) const {
  bool down = true;
  if (uses_spindle_) down = down && spindle_on_;
  if (uses_servo_) down = down && servo_down_;
  if (uses_z_) down = down && z_known && machine[2] - offset_[2] <= options_.pen_z_threshold;
  return down;
}

void Interpreter::Move(const Block& block, int motion, const Point3& target, bool z_known_after) {
  const bool any_pen = uses_spindle_ || uses_servo_ || uses_z_;
  const bool drawn =
      any_pen ? PenDownAt(position_, z_known_) && PenDownAt(target, z_known_after) : motion != 0;
  if (motion == 50) {
    Cubic(block, target, drawn);
  } else {
    previous_g5_pq_.reset();
    if (motion == 20 || motion == 30) {
      Arc(block, motion == 20, target, drawn);
    } else if (motion == 51) {
      Quadratic(block, target, drawn);
    } else if (drawn && target != position_) {
      const Point3& a = position_;
      std::array<Point3, 4> g{};
      for (std::size_t c = 0; c < 3; ++c) {
        g[0][c] = a[c];
        g[1][c] = a[c] + (target[c] - a[c]) / 3;
        g[2][c] = a[c] + 2 * (target[c] - a[c]) / 3;
        g[3][c] = target[c];
      }
      AddCurve(g, block.line, CodeName('G', motion), true);
    }
  }
  position_ = target;
  z_known_ = z_known_after;
}

void Interpreter::AddCurve(const std::array<Point3, 4>& g, int line, const std::string& code,
                           bool straight) {
  Curve curve;
  curve.basis = Basis::kBezier;
  curve.g = g;
  curve.origin = name_ + ":" + std::to_string(line) + " (" + code + ")";
  curve.layer = layer_;
  curve.straight = straight;
  set_.curves.push_back(std::move(curve));
}

void Interpreter::NewLayer(const std::string& name) {
  layer_names_.push_back(name);
  layer_ = static_cast<int>(layer_names_.size()) - 1;
}

// The arc's centre from R: on the chord's perpendicular bisector, to the
// right of the chord (start to end) for a clockwise arc with R > 0 (under
// 180°), to the left for a counter-clockwise one; R < 0 takes the other side
// (the arc over 180°). Grbl's wiki and LinuxCNC's reference give this rule.
std::array<double, 2> CentreFromRadius(double sa, double sb, double ea, double eb, double r,
                                       bool clockwise,
                                       const std::function<InputError(const std::string&)>& fail) {
  const double da = ea - sa;
  const double db = eb - sb;
  const double d = std::hypot(da, db);
  const double half = d / 2;
  if (std::fabs(r) < half && half - std::fabs(r) > 1e-9 * std::max(1.0, half)) {
    throw fail("R " + FormatNumber(std::fabs(r)) + " is less than half the distance " +
               FormatNumber(d) + " to the end point");
  }
  const double h = std::sqrt(std::max(0.0, r * r - half * half));
  double side = clockwise ? 1 : -1;
  if (r < 0) side = -side;
  // (db, −da)/d points to the right of the chord.
  return {sa + da / 2 + side * h * db / d, sb + db / 2 - side * h * da / d};
}

void Interpreter::Arc(const Block& block, bool clockwise, const Point3& target, bool drawn) {
  const PlaneAxes p = AxesOf(plane_);
  const std::string code = clockwise ? "G2" : "G3";
  const auto fail = [&](const std::string& what) { return Error(block.line, code + ": " + what); };
  const char normal_letter = "IJK"[p.n];
  if (block.Has(normal_letter)) {
    throw fail(std::string(1, normal_letter) + " is not an offset in the " + p.name + " plane");
  }
  const std::string offset_names = std::string(1, std::min(p.offset_a, p.offset_b)) + "/" +
                                   std::string(1, std::max(p.offset_a, p.offset_b));
  const bool has_offsets = block.Has(p.offset_a) || block.Has(p.offset_b);
  if (block.Has('R') && has_offsets) throw fail("R and " + offset_names + " given together");
  if (!block.Has('R') && !has_offsets) throw fail("neither R nor " + offset_names + " given");
  const double sa = position_[p.a];
  const double sb = position_[p.b];
  const double ea = target[p.a];
  const double eb = target[p.b];
  const bool closed = sa == ea && sb == eb;
  std::array<double, 2> centre{};
  if (block.Has('R')) {
    if (closed) {
      throw fail("R with the end point at the start (a full circle needs " + offset_names + ")");
    }
    centre = CentreFromRadius(sa, sb, ea, eb, Length(*block.Get('R'), block.line), clockwise, fail);
  } else {
    const auto offset = [&](char letter, std::size_t axis, double start) {
      const std::optional<double> value = block.Get(letter);
      if (!value) return start;
      const double length = Length(*value, block.line);
      return arc_centre_absolute_ ? length + offset_[axis] : start + length;
    };
    centre = {offset(p.offset_a, p.a, sa), offset(p.offset_b, p.b, sb)};
  }
  const double r0 = std::hypot(sa - centre[0], sb - centre[1]);
  const double r1 = std::hypot(ea - centre[0], eb - centre[1]);
  if (r0 == 0) throw fail("the centre is at the start point");
  // Grbl's rule for an end point off the circle: refused when it is more
  // than 0.5 mm off, or more than 0.005 mm and 0.1 % of the radius.
  const double mismatch = std::fabs(r1 - r0);
  const double mismatch_mm = mismatch * (unit_ == "in" ? 25.4 : 1);
  if (mismatch_mm > 0.5 || (mismatch_mm > 0.005 && mismatch > 0.001 * r0)) {
    throw fail("the end point is not on the arc: it is " + FormatNumber(r1) +
               " from the centre, the start " + FormatNumber(r0));
  }
  const double a0 = std::atan2(sb - centre[1], sa - centre[0]);
  const double a1 = std::atan2(eb - centre[1], ea - centre[0]);
  double sweep = clockwise ? a0 - a1 : a1 - a0;
  if (closed) {
    sweep = 2 * kPi;
  } else {
    while (sweep <= 0) sweep += 2 * kPi;
    while (sweep > 2 * kPi) sweep -= 2 * kPi;
  }
  if (const std::optional<double> turns = block.Get('P')) {
    if (*turns < 1 || *turns != std::floor(*turns) || *turns > 1000) {
      throw fail("P (turns) must be a whole number from 1 to 1000");
    }
    sweep += 2 * kPi * (*turns - 1);
  }
  if (!drawn) return;
  if (position_[p.n] != target[p.n] && !drawn_helix_noted_) {
    drawn_helix_noted_ = true;
    Note("helix", block.line,
         code + ": a helical move; its arc is drawn within the arc tolerance in its plane, its " +
             std::string(1, "XYZ"[p.n]) + " moving linearly within each piece of at most 90°");
  }
  AddArcPieces(block.line, code, p, centre, r0, a0, clockwise ? -sweep : sweep, target);
}

// The arc as the standard cubics of the circle (CircleArcToCubics), each
// within the arc tolerance of the circle in the plane; along the plane's
// normal (a helix) each piece moves linearly. The ends are the machine's
// position and the target: rounding moves them a little (the margin, taken
// off the tolerance), an end point off the circle by what it is off (noted
// when that is more than a quarter of the tolerance, which it then leaves).
void Interpreter::AddArcPieces(int line, const std::string& code, const PlaneAxes& p,
                               const std::array<double, 2>& centre, double radius, double start,
                               double sweep, const Point3& target) {
  const auto in_plane = [&](double angle) {
    return PlanePoint{centre[0] + radius * std::cos(angle), centre[1] + radius * std::sin(angle)};
  };
  const auto off = [&](const PlanePoint& q, const Point3& machine) {
    return std::hypot(q[0] - machine[p.a], q[1] - machine[p.b]);
  };
  const double tolerance = options_.arc_tolerance;
  const double end_off = off(in_plane(start + sweep), target);
  if (end_off > tolerance / 4) {
    Note("arc end " + std::to_string(line), line,
         code + ": the end point is " + FormatNumber(end_off) +
             " off the circle; the last piece is bent by at most that to meet it");
  }
  // 32 ε of the coordinates' size is generous for the few operations that
  // make a control point (docs/formats.md, "Circular and elliptical arcs").
  const double margin =
      32 * std::numeric_limits<double>::epsilon() *
          (std::fabs(centre[0]) + std::fabs(centre[1]) + 2 * radius) +
      std::max(off(in_plane(start), position_), end_off > tolerance / 4 ? 0 : end_off);
  if (!(margin < tolerance / 2)) {
    throw Error(line, code +
                          ": the arc cannot be drawn within the arc tolerance "
                          "(--arc-tolerance) " +
                          FormatNumber(tolerance) + ": rounding alone moves it by " +
                          FormatNumber(margin));
  }
  CircleArcCubics pieces;
  try {
    pieces = CircleArcToCubics(start, sweep, radius, tolerance - margin);
  } catch (const ConstructionError& e) {
    throw Error(line, code + ": " + e.what());
  }
  const double n = static_cast<double>(pieces.cubics.size());
  const double lin0 = position_[p.n];
  const double lin1 = target[p.n];
  Point3 from = position_;
  for (std::size_t k = 0; k < pieces.cubics.size(); ++k) {
    const bool last = k + 1 == pieces.cubics.size();
    std::array<Point3, 4> g{};
    for (std::size_t i = 0; i < 4; ++i) {
      const double f = (static_cast<double>(k) + static_cast<double>(i) / 3) / n;
      g[i][p.a] = centre[0] + radius * pieces.cubics[k][i][0];
      g[i][p.b] = centre[1] + radius * pieces.cubics[k][i][1];
      g[i][p.n] = lin0 + (lin1 - lin0) * f;
    }
    g[0] = from;
    if (last) g[3] = target;
    AddCurve(g, line, code, false);
    from = g[3];
  }
}

// G5: the cubic Bézier curve from here to the target with control points
// here + (I, J) and target + (P, Q) (LinuxCNC, Marlin). Without I and J it
// continues the previous G5 smoothly: I, J = −(P, Q) of that one.
void Interpreter::Cubic(const Block& block, const Point3& target, bool drawn) {
  const auto fail = [&](const std::string& what) { return Error(block.line, "G5: " + what); };
  if (plane_ != 17) throw fail("needs the XY plane (G17)");
  if (block.Has('Z')) throw fail("Z is not allowed (G5 moves in X and Y only)");
  if (!block.Has('P') || !block.Has('Q')) throw fail("P and Q are both required");
  if (block.Has('I') != block.Has('J')) throw fail("I and J must be given together");
  std::array<double, 2> ij{};
  if (block.Has('I')) {
    ij = {Length(*block.Get('I'), block.line), Length(*block.Get('J'), block.line)};
  } else if (previous_g5_pq_) {
    ij = {-(*previous_g5_pq_)[0], -(*previous_g5_pq_)[1]};
  } else {
    throw fail("I and J are required on the first G5 of a series");
  }
  const std::array<double, 2> pq = {Length(*block.Get('P'), block.line),
                                    Length(*block.Get('Q'), block.line)};
  previous_g5_pq_ = pq;
  if (!drawn) return;
  const Point3& s = position_;
  const std::array<Point3, 4> g = {s, Point3{s[0] + ij[0], s[1] + ij[1], s[2]},
                                   Point3{target[0] + pq[0], target[1] + pq[1], s[2]}, target};
  AddCurve(g, block.line, "G5", false);
}

// G5.1: the quadratic Bézier curve with control point here + (I, J), raised
// to a cubic exactly (b1 = p0 + 2/3·(q − p0), b2 = p2 + 2/3·(q − p2)).
void Interpreter::Quadratic(const Block& block, const Point3& target, bool drawn) {
  const auto fail = [&](const std::string& what) { return Error(block.line, "G5.1: " + what); };
  if (plane_ != 17) throw fail("needs the XY plane (G17)");
  if (block.Has('Z')) throw fail("Z is not allowed (G5.1 moves in X and Y only)");
  if (block.Has('P') || block.Has('Q')) throw fail("P and Q are not G5.1 words (G5 has them)");
  const double i = block.Has('I') ? Length(*block.Get('I'), block.line) : 0;
  const double j = block.Has('J') ? Length(*block.Get('J'), block.line) : 0;
  if (i == 0 && j == 0) throw fail("I and J are both zero or missing");
  if (!drawn) return;
  const Point3& s = position_;
  const Point3 q = {s[0] + i, s[1] + j, s[2]};
  std::array<Point3, 4> g = {s, s, target, target};
  for (std::size_t c = 0; c < 2; ++c) {
    g[1][c] = s[c] + 2 * (q[c] - s[c]) / 3;
    g[2][c] = target[c] + 2 * (q[c] - target[c]) / 3;
  }
  AddCurve(g, block.line, "G5.1", false);
}

PatchSet Interpreter::Finish() {
  if (set_.curves.empty()) {
    throw InputError(name_ + ": the program draws nothing (no move with the pen down)");
  }
  set_.units = unit_.empty() ? "mm" : unit_;
  set_.keep_order = true;
  if (layer_names_.size() > 1) {
    // Layers without curves (two pauses in a row) are left out.
    std::vector<int> used(layer_names_.size(), 0);
    for (const Curve& curve : set_.curves) used[static_cast<std::size_t>(curve.layer)] = 1;
    std::vector<int> index(layer_names_.size(), -1);
    for (std::size_t l = 0; l < layer_names_.size(); ++l) {
      if (used[l] == 0) continue;
      index[l] = static_cast<int>(set_.layers.size());
      set_.layers.push_back(layer_names_[l]);
    }
    for (Curve& curve : set_.curves) curve.layer = index[static_cast<std::size_t>(curve.layer)];
  }
  return std::move(set_);
}

}  // namespace

PatchSet ReadGcode(const std::string& text, const std::string& name,
                   const GcodeReadOptions& options) {
  if (!(options.arc_tolerance > 0) || !std::isfinite(options.arc_tolerance)) {
    throw OptionError("arc tolerance", FormatNumber(options.arc_tolerance), "must be > 0");
  }
  Interpreter interpreter(name, options);
  interpreter.Run(gcode::SplitLines(text, name));
  return interpreter.Finish();
}

}  // namespace fdsurf::host
