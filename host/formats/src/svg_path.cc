// SPDX-License-Identifier: MIT
// The SVG 2 path grammar (https://www.w3.org/TR/SVG2/paths.html#PathDataBNF):
// every command, absolute and relative, implicit repeats (a moveto's extra
// pairs are linetos), the compact number forms ("-.5.5" is -0.5 0.5, "1e-3")
// and arc flags written without separators ("a1 1 0 015 5").
#include <cctype>
#include <charconv>
#include <cmath>
#include <string>

#include "svg_internal.h"

namespace fdsurf::host::svg {
namespace {

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f'; }
bool IsDigit(char c) { return c >= '0' && c <= '9'; }

// Reads numbers and flags from one attribute value, reporting columns.
class Scanner {
 public:
  explicit Scanner(std::string_view text) : text_(text) {}

  void SkipSpace() {
    while (pos_ < text_.size() && IsSpace(text_[pos_])) ++pos_;
  }
  // White space with at most one comma in it.
  void SkipCommaSpace() {
    SkipSpace();
    if (pos_ < text_.size() && text_[pos_] == ',') {
      ++pos_;
      SkipSpace();
    }
  }
  FDSURF_NODISCARD bool AtEnd() const { return pos_ >= text_.size(); }
  FDSURF_NODISCARD char Peek() const { return AtEnd() ? '\0' : text_[pos_]; }
  char Take() { return text_[pos_++]; }
  FDSURF_NODISCARD std::size_t Column() const { return pos_ + 1; }

  // Whether a number starts here.
  FDSURF_NODISCARD bool AtNumber() const {
    const char c = Peek();
    return IsDigit(c) || c == '-' || c == '+' || c == '.';
  }

  // A number per the grammar's `number`; nullopt-like false when none.
  bool Number(double* value) {
    const std::size_t start = pos_;
    std::size_t p = pos_;
    if (p < text_.size() && (text_[p] == '-' || text_[p] == '+')) ++p;
    const std::size_t digits_start = p;
    while (p < text_.size() && IsDigit(text_[p])) ++p;
    bool digits = p > digits_start;
    if (p < text_.size() && text_[p] == '.') {
      const std::size_t fraction = ++p;
      while (p < text_.size() && IsDigit(text_[p])) ++p;
      digits = digits || p > fraction;
    }
    if (!digits) return false;
    // An exponent only when digits follow it ("1e" is 1 and then 'e').
    if (p < text_.size() && (text_[p] == 'e' || text_[p] == 'E')) {
      std::size_t q = p + 1;
      if (q < text_.size() && (text_[q] == '-' || text_[q] == '+')) ++q;
      if (q < text_.size() && IsDigit(text_[q])) {
        while (q < text_.size() && IsDigit(text_[q])) ++q;
        p = q;
      }
    }
    // from_chars takes no '+'.
    const std::size_t from = text_[start] == '+' ? start + 1 : start;
    const auto [end, ec] = std::from_chars(text_.data() + from, text_.data() + p, *value);
    if (ec == std::errc::result_out_of_range || !std::isfinite(*value)) {
      throw SyntaxError("number '" + std::string(text_.substr(start, p - start)) +
                        "' is out of range at column " + std::to_string(start + 1));
    }
    if (ec != std::errc() || end != text_.data() + p) {
      throw SyntaxError("malformed number at column " + std::to_string(start + 1));
    }
    pos_ = p;
    return true;
  }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
};

// The state of one path: where the pen is, where the subpath began, and the
// control point that S/s and T/t reflect.
class PathParser {
 public:
  PathParser(std::string_view d, PathSink* sink) : scan_(d), sink_(sink) {}

  void Run() {
    scan_.SkipSpace();
    if (scan_.AtEnd()) return;
    if (scan_.Peek() != 'M' && scan_.Peek() != 'm') {
      throw SyntaxError("path data must start with 'M' or 'm', not '" +
                        std::string(1, scan_.Peek()) + "' at column " +
                        std::to_string(scan_.Column()));
    }
    while (true) {
      scan_.SkipSpace();
      if (scan_.AtEnd()) return;
      const std::size_t column = scan_.Column();
      const char command = scan_.Take();
      if (std::string_view("MmLlHhVvCcSsQqTtAaZz").find(command) == std::string_view::npos) {
        throw SyntaxError("unknown path command '" + std::string(1, command) + "' at column " +
                          std::to_string(column));
      }
      Command(command);
    }
  }

 private:
  // A number after `command`, which needs one.
  double Need(char command) {
    scan_.SkipCommaSpace();
    double value = 0;
    if (!scan_.Number(&value)) {
      throw SyntaxError(std::string("expected a number after '") + command + "' at column " +
                        std::to_string(scan_.Column()));
    }
    return value;
  }
  Vec2 NeedPoint(char command, bool relative) {
    const double x = Need(command);
    const double y = Need(command);
    return relative ? Vec2{current_[0] + x, current_[1] + y} : Vec2{x, y};
  }
  bool NeedFlag(char command) {
    scan_.SkipCommaSpace();
    const char c = scan_.Peek();
    if (c != '0' && c != '1') {
      throw SyntaxError(std::string("expected a flag 0 or 1 after '") + command + "' at column " +
                        std::to_string(scan_.Column()));
    }
    scan_.Take();
    return c == '1';
  }
  // Another set of arguments follows (an implicit repeat of the command).
  bool MoreArguments() {
    scan_.SkipCommaSpace();
    return scan_.AtNumber();
  }

  void Command(char command) {
    const bool relative = std::islower(static_cast<unsigned char>(command)) != 0;
    const char upper = static_cast<char>(std::toupper(static_cast<unsigned char>(command)));
    if (upper == 'Z') {
      if (current_ != start_) sink_->Line(current_, start_);
      current_ = start_;
      last_control_ = current_;
      last_ = 'Z';
      return;
    }
    bool first = true;
    do {
      Segment(upper, command, relative, first);
      first = false;
    } while (MoreArguments());
  }

  void Segment(char upper, char command, bool relative, bool first) {
    Vec2 control = current_;
    char kind = upper;
    switch (upper) {
      case 'M': {
        const Vec2 to = NeedPoint(command, relative);
        if (first) {
          current_ = start_ = to;
        } else {  // the extra pairs of a moveto are linetos
          sink_->Line(current_, to);
          current_ = to;
          kind = 'L';
        }
        break;
      }
      case 'L':
      case 'H':
      case 'V': {
        Vec2 to = current_;
        if (upper == 'L') to = NeedPoint(command, relative);
        if (upper == 'H') to[0] = Need(command) + (relative ? current_[0] : 0);
        if (upper == 'V') to[1] = Need(command) + (relative ? current_[1] : 0);
        sink_->Line(current_, to);
        current_ = to;
        break;
      }
      case 'C':
      case 'S': {
        const Vec2 p1 = upper == 'C' ? NeedPoint(command, relative) : Reflected("CS");
        const Vec2 p2 = NeedPoint(command, relative);
        const Vec2 p3 = NeedPoint(command, relative);
        sink_->Cubic(current_, p1, p2, p3);
        control = p2;
        current_ = p3;
        break;
      }
      case 'Q':
      case 'T': {
        const Vec2 q = upper == 'Q' ? NeedPoint(command, relative) : Reflected("QT");
        const Vec2 p3 = NeedPoint(command, relative);
        // Degree elevation, exact: the cubic's inner points are 1/3 and 2/3
        // of the way to the quadratic's control point.
        const Vec2 p1{current_[0] + 2.0 / 3.0 * (q[0] - current_[0]),
                      current_[1] + 2.0 / 3.0 * (q[1] - current_[1])};
        const Vec2 p2{p3[0] + 2.0 / 3.0 * (q[0] - p3[0]), p3[1] + 2.0 / 3.0 * (q[1] - p3[1])};
        sink_->Cubic(current_, p1, p2, p3);
        control = q;
        current_ = p3;
        break;
      }
      default: {  // 'A'
        const double rx = Need(command);
        const double ry = Need(command);
        const double rotation = Need(command);
        const bool large = NeedFlag(command);
        const bool sweep = NeedFlag(command);
        const Vec2 to = NeedPoint(command, relative);
        sink_->Arc(current_, rx, ry, rotation, large, sweep, to);
        current_ = to;
        break;
      }
    }
    last_control_ = control;
    last_ = kind;
  }

  // S's and T's first control point: the previous one reflected about the
  // current point when the previous command was of the same family
  // (`family`: "CS" or "QT"), else the current point.
  FDSURF_NODISCARD Vec2 Reflected(std::string_view family) const {
    if (family.find(last_) == std::string_view::npos) return current_;
    return {2 * current_[0] - last_control_[0], 2 * current_[1] - last_control_[1]};
  }

  Scanner scan_;
  PathSink* sink_;
  Vec2 current_{};
  Vec2 start_{};
  Vec2 last_control_{};
  char last_ = 'M';
};

}  // namespace

void ParsePathData(std::string_view d, PathSink* sink) { PathParser(d, sink).Run(); }

std::vector<double> ParseNumberList(std::string_view text) {
  Scanner scan(text);
  std::vector<double> numbers;
  scan.SkipSpace();
  while (!scan.AtEnd()) {
    double value = 0;
    if (!scan.Number(&value)) {
      throw SyntaxError("expected a number at column " + std::to_string(scan.Column()));
    }
    numbers.push_back(value);
    scan.SkipCommaSpace();
  }
  return numbers;
}

double MillimetresPerUnit(std::string_view unit) {
  if (unit.empty() || unit == "px") return 25.4 / 96;
  if (unit == "mm") return 1;
  if (unit == "cm") return 10;
  if (unit == "in") return 25.4;
  if (unit == "pt") return 25.4 / 72;
  if (unit == "pc") return 25.4 / 6;
  return 0;
}

double ParseLength(std::string_view text) {
  Scanner scan(text);
  scan.SkipSpace();
  double value = 0;
  if (!scan.Number(&value)) throw SyntaxError("expected a length at column 1");
  std::size_t unit_start = scan.Column() - 1;
  std::size_t unit_end = text.size();
  while (unit_end > unit_start && IsSpace(text[unit_end - 1])) --unit_end;
  const std::string_view unit = text.substr(unit_start, unit_end - unit_start);
  if (unit == "%") throw SyntaxError("percentage lengths are not supported");
  const double mm = MillimetresPerUnit(unit);
  if (mm == 0) {
    throw SyntaxError("unknown unit '" + std::string(unit) +
                      "' (expected mm, cm, in, pt, pc, px or none)");
  }
  return value * mm / (25.4 / 96);
}

}  // namespace fdsurf::host::svg
