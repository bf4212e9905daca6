// SPDX-License-Identifier: MIT
// SVG transforms (https://www.w3.org/TR/SVG2/coords.html#TransformAttribute)
// and the endpoint-to-centre conversion of elliptical arcs (SVG 2 appendix
// B.2.4, https://www.w3.org/TR/SVG2/implnote.html#ArcConversionEndpointToCenter).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <string>

#include "svg_internal.h"

namespace fdsurf::host::svg {

Affine Affine::After(const Affine& inner) const {
  return {a * inner.a + c * inner.b, b * inner.a + d * inner.b,     a * inner.c + c * inner.d,
          b * inner.c + d * inner.d, a * inner.e + c * inner.f + e, b * inner.e + d * inner.f + f};
}

double Affine::MaxStretch() const {
  // σ_max² is the larger eigenvalue of LᵀL: (S + sqrt(S² − 4·det²)) / 2 with
  // S = a² + b² + c² + d² (the squared Frobenius norm) and det = ad − bc.
  const double s = a * a + b * b + c * c + d * d;
  const double det = a * d - b * c;
  const double disc = std::max(0.0, s * s - 4 * det * det);
  return std::sqrt((s + std::sqrt(disc)) / 2);
}

namespace {

constexpr double kDegree = std::numbers::pi / 180;

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f'; }

// One transform function with its arguments; `column` for messages.
Affine TransformFunction(std::string_view name, const std::vector<double>& v, std::size_t column) {
  const std::size_t n = v.size();
  auto arity_error = [&](const char* expected) {
    return SyntaxError(std::string(name) + "() takes " + expected + ", not " + std::to_string(n) +
                       " at column " + std::to_string(column));
  };
  if (name == "matrix") {
    if (n != 6) throw arity_error("6 numbers");
    return {v[0], v[1], v[2], v[3], v[4], v[5]};
  }
  if (name == "translate") {
    if (n != 1 && n != 2) throw arity_error("1 or 2 numbers");
    return {1, 0, 0, 1, v[0], n == 2 ? v[1] : 0};
  }
  if (name == "scale") {
    if (n != 1 && n != 2) throw arity_error("1 or 2 numbers");
    return {v[0], 0, 0, n == 2 ? v[1] : v[0], 0, 0};
  }
  if (name == "rotate") {
    if (n != 1 && n != 3) throw arity_error("1 or 3 numbers");
    const double cs = std::cos(v[0] * kDegree);
    const double sn = std::sin(v[0] * kDegree);
    const Affine turn{cs, sn, -sn, cs, 0, 0};
    if (n == 1) return turn;
    // rotate(a, cx, cy) = translate(cx, cy) rotate(a) translate(-cx, -cy).
    return Affine{1, 0, 0, 1, v[1], v[2]}.After(turn.After({1, 0, 0, 1, -v[1], -v[2]}));
  }
  if (name == "skewX" || name == "skewY") {
    if (n != 1) throw arity_error("1 number");
    const double t = std::tan(v[0] * kDegree);
    return name == "skewX" ? Affine{1, 0, t, 1, 0, 0} : Affine{1, t, 0, 1, 0, 0};
  }
  throw SyntaxError("unknown transform '" + std::string(name) + "' at column " +
                    std::to_string(column));
}

}  // namespace

Affine ParseTransform(std::string_view text) {
  Affine result;
  std::size_t pos = 0;
  auto skip = [&] {
    while (pos < text.size() && (IsSpace(text[pos]) || text[pos] == ',')) ++pos;
  };
  skip();
  while (pos < text.size()) {
    const std::size_t column = pos + 1;
    std::size_t name_end = pos;
    while (name_end < text.size() && std::isalpha(static_cast<unsigned char>(text[name_end]))) {
      ++name_end;
    }
    const std::string_view name = text.substr(pos, name_end - pos);
    std::size_t open = name_end;
    while (open < text.size() && IsSpace(text[open])) ++open;
    if (name.empty() || open >= text.size() || text[open] != '(') {
      throw SyntaxError("expected a transform such as translate(...) at column " +
                        std::to_string(column));
    }
    const std::size_t close = text.find(')', open);
    if (close == std::string_view::npos) {
      throw SyntaxError("missing ')' after " + std::string(name) + "( at column " +
                        std::to_string(column));
    }
    std::vector<double> args;
    try {
      args = ParseNumberList(text.substr(open + 1, close - open - 1));
    } catch (const SyntaxError&) {
      throw SyntaxError("malformed arguments of " + std::string(name) + "() at column " +
                        std::to_string(column));
    }
    // The list applies right to left: the first function is the outermost.
    result = result.After(TransformFunction(name, args, column));
    pos = close + 1;
    skip();
  }
  return result;
}

Vec2 CentreArc::At(double theta) const {
  const double cs = std::cos(rotation);
  const double sn = std::sin(rotation);
  const double x = rx * std::cos(theta);
  const double y = ry * std::sin(theta);
  return {centre[0] + cs * x - sn * y, centre[1] + sn * x + cs * y};
}

CentreArc EndpointToCentre(const Vec2& from, double rx, double ry, double rotation_deg,
                           bool large_arc, bool sweep, const Vec2& to) {
  CentreArc arc;
  arc.rotation = std::fmod(rotation_deg, 360.0) * kDegree;
  const double cs = std::cos(arc.rotation);
  const double sn = std::sin(arc.rotation);
  // Step 1: the midpoint difference in the ellipse's own axes.
  const double hx = (from[0] - to[0]) / 2;
  const double hy = (from[1] - to[1]) / 2;
  const double x1 = cs * hx + sn * hy;
  const double y1 = -sn * hx + cs * hy;
  // B.2.5: radii made positive and scaled up until the ends fit.
  rx = std::abs(rx);
  ry = std::abs(ry);
  const double lambda = (x1 * x1) / (rx * rx) + (y1 * y1) / (ry * ry);
  if (lambda > 1) {
    rx *= std::sqrt(lambda);
    ry *= std::sqrt(lambda);
  }
  // Step 2: the centre in those axes (the radicand is 0 up to rounding when
  // the radii were scaled).
  const double num = rx * rx * ry * ry - rx * rx * y1 * y1 - ry * ry * x1 * x1;
  const double den = rx * rx * y1 * y1 + ry * ry * x1 * x1;
  double coef = std::sqrt(std::max(0.0, num / den));
  if (large_arc == sweep) coef = -coef;
  const double cx1 = coef * rx * y1 / ry;
  const double cy1 = -coef * ry * x1 / rx;
  // Step 3: back to user space.
  arc.centre = {cs * cx1 - sn * cy1 + (from[0] + to[0]) / 2,
                sn * cx1 + cs * cy1 + (from[1] + to[1]) / 2};
  arc.rx = rx;
  arc.ry = ry;
  // Step 4: the angles, from the unit circle's points.
  const double ux = (x1 - cx1) / rx;
  const double uy = (y1 - cy1) / ry;
  const double vx = (-x1 - cx1) / rx;
  const double vy = (-y1 - cy1) / ry;
  arc.theta1 = std::atan2(uy, ux);
  double delta = std::atan2(ux * vy - uy * vx, ux * vx + uy * vy);
  if (!sweep && delta > 0) delta -= 2 * std::numbers::pi;
  if (sweep && delta < 0) delta += 2 * std::numbers::pi;
  arc.delta = delta;
  return arc;
}

}  // namespace fdsurf::host::svg
