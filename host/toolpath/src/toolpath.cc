// SPDX-License-Identifier: MIT
#include "fdsurf/host/toolpath.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "fdsurf/forward_difference.h"
#include "fdsurf/host/constructions.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/reference.h"
#include "fdsurf/host/text.h"

namespace fdsurf::host {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::array<double, 3> Cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

double Dot(const std::array<double, 3>& a, const Point3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// The range of a·u³ + b·u² + c·u + d over [0, 1]: the ends and the roots of
// the derivative inside.
std::array<double, 2> CubicRange(double a, double b, double c, double d) {
  const auto f = [&](double u) { return ((a * u + b) * u + c) * u + d; };
  double lo = std::min(f(0), f(1));
  double hi = std::max(f(0), f(1));
  const auto consider = [&](double u) {
    if (u > 0 && u < 1) {
      lo = std::min(lo, f(u));
      hi = std::max(hi, f(u));
    }
  };
  // The roots of 3a·u² + 2b·u + c in the stable form q/qa and qc/q, with
  // q = −(qb + sign(qb)·√disc)/2: the textbook (−qb ± √disc)/2qa cancels
  // when a is tiny (a line whose cubic term is rounding noise, as on the
  // teapot's bottom) and lost the extremum, 9 steps of it (issue 12).
  const double qa = 3 * a, qb = 2 * b, qc = c;
  const double disc = qb * qb - 4 * qa * qc;
  if (disc >= 0) {
    const double q = -(qb + std::copysign(std::sqrt(disc), qb)) / 2;
    if (q != 0) consider(qc / q);
    if (qa != 0) consider(q / qa);
  }
  return {lo, hi};
}

// The power coefficients (model space) of one isoline of a patch:
// coefficient l multiplies u^(3-l) along the line.
std::array<Point3, 4> LineCoefficients(const PowerCoefficients& pc, IsolineFamily family,
                                       double at) {
  const double powers[4] = {at * at * at, at * at, at, 1};
  std::array<Point3, 4> line{};
  for (int l = 0; l < 4; ++l) {
    for (int k = 0; k < 4; ++k) {
      const Point3& c = family == IsolineFamily::kSLines ? pc.c[k][l] : pc.c[l][k];
      for (int axis = 0; axis < 3; ++axis) line[l][axis] += powers[k] * c[axis];
    }
  }
  return line;
}

double LineParam(int i, int lines) {
  return lines == 1 ? 0.0 : static_cast<double>(i) / (lines - 1);
}

struct Box {
  std::array<double, 3> lo{HUGE_VAL, HUGE_VAL, HUGE_VAL};
  std::array<double, 3> hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
};

// The exact bounding box of the drawn isolines in view coordinates at scale 1.
Box DrawingBox(const PatchSet& set, const ToolpathOptions& options) {
  Box box;
  for (const Patch& patch : set.patches) {
    const PowerCoefficients pc = CoefficientsOf(patch);
    const auto family_box = [&](IsolineFamily family, int lines) {
      for (int i = 0; i < lines; ++i) {
        const auto line = LineCoefficients(pc, family, LineParam(i, lines));
        const std::array<double, 3>* axes[3] = {&options.view.right, &options.view.up,
                                                &options.view.depth};
        for (int a = 0; a < 3; ++a) {
          const auto range = CubicRange(Dot(*axes[a], line[0]), Dot(*axes[a], line[1]),
                                        Dot(*axes[a], line[2]), Dot(*axes[a], line[3]));
          box.lo[a] = std::min(box.lo[a], range[0]);
          box.hi[a] = std::max(box.hi[a], range[1]);
        }
      }
    };
    family_box(IsolineFamily::kSLines, options.lines_s);
    family_box(IsolineFamily::kTLines, options.lines_t);
  }
  for (const Curve& curve : set.curves) {
    const VecPoly p = CurvePolynomial(curve);  // ascending powers
    const std::array<double, 3>* axes[3] = {&options.view.right, &options.view.up,
                                            &options.view.depth};
    for (int a = 0; a < 3; ++a) {
      const auto range = CubicRange(Dot(*axes[a], p[3]), Dot(*axes[a], p[2]), Dot(*axes[a], p[1]),
                                    Dot(*axes[a], p[0]));
      box.lo[a] = std::min(box.lo[a], range[0]);
      box.hi[a] = std::max(box.hi[a], range[1]);
    }
  }
  return box;
}

// Whether G[i][j] is a point (moves with the offset) or a vector (does not):
// Hermite tangents and twists, and every power coefficient but the constant.
bool IsPoint(Basis basis, int i, int j) {
  switch (basis) {
    case Basis::kHermite:
      return i < 2 && j < 2;
    case Basis::kPower:
      return i == 3 && j == 3;
    default:
      return true;
  }
}

// The same for a curve's geometry: Hermite tangents and the power
// coefficients but the constant are vectors.
bool IsCurvePoint(Basis basis, int k) {
  switch (basis) {
    case Basis::kHermite:
      return k < 2;
    case Basis::kPower:
      return k == 3;
    default:
      return true;
  }
}

constexpr double kInverseSqrt[4] = {0, 1.0, 0.70710678118654752, 0.57735026918962576};

// Why the engine refused a line, for the person who asked for it.
[[noreturn]] void Refuse(const ToolpathOptions& options, Status status, const std::string& where) {
  std::string why = where + ": ";
  switch (status) {
    case Status::kPrecisionUnreachable:
      why += options.mode == StepMode::kStepExact
                 ? "a step-exact path would need steps below 2^-30 of the curve or more than 128 "
                   "accumulator bits; use a coarser quantum"
                 : "the tolerance needs steps below 2^-30 of the curve; use a larger tolerance";
      break;
    case Status::kGeometryOutOfRange:
      why += "the curve could reach ±2^31 quanta; use a coarser quantum";
      break;
    default:
      why += StatusMessage(status);
  }
  throw EngineError(why);
}

// Steps one cubic (power coefficients in 2^-16 quanta) into `stroke`, as the
// options say: adaptive or step-exact forward differences, or the fewest
// uniform steps that keep the tolerance. `where` names the line in errors.
template <int kDims>
void StepLine(const PowerCurve1 (&curve)[kDims], const ToolpathOptions& options,
              const std::string& where, Stroke* stroke) {
  const double tolerance_q = options.tolerance / options.quantum.value();
  const auto add = [&](double param, const std::int32_t(&p)[kDims]) {
    std::array<std::int64_t, 3> point{0, 0, 0};
    for (int c = 0; c < kDims; ++c) point[c] = p[c];
    // A repeated point draws nothing; the chord to the next point covers
    // both parameter intervals (each is within the tolerance of it).
    if (!stroke->points.empty() && stroke->points.back() == point) return;
    stroke->points.push_back(point);
    stroke->params.push_back(param);
  };
  if (options.mode == StepMode::kFixed) {
    // The fewest uniform steps N with √d/8·max|x''|/N² + √d·0.511 ≤ tolerance (0.51 stepping,
    // 2^-12 geometry and coefficient rounding).
    double second = 0;
    for (int c = 0; c < kDims; ++c) {
      second = std::max(second, (6 * std::fabs(static_cast<double>(curve[c].c[0])) +
                                 2 * std::fabs(static_cast<double>(curve[c].c[1]))) /
                                    65536.0);
    }
    const double budget = tolerance_q * kInverseSqrt[kDims] - 0.511;
    const double n = std::max(1.0, std::ceil(std::sqrt(second / (8 * budget)) * (1 + 1e-12)));
    if (!(n <= kMaxCurveSteps)) Refuse(options, Status::kPrecisionUnreachable, where);
    CurveGeometry1 power[kDims];
    for (int c = 0; c < kDims; ++c) {
      for (int k = 0; k < 4; ++k) power[c].g[k] = GeometryFixed::FromRaw(curve[c].c[k]);
    }
    PreparedCurve<kDims> prepared;
    const Status status = PrepareCurve(power, Basis::kPower, static_cast<std::uint16_t>(n),
                                       PrepareOptions{}, &prepared);
    if (status != Status::kOk) Refuse(options, status, where);
    const auto sink = [&](std::uint32_t k, const std::int32_t(&p)[kDims]) { add(k / n, p); };
    if (prepared.format.acc_bits == 64) {
      CurveStepper<std::int64_t, kDims>(prepared).ForEachPoint(sink);
    } else {
      CurveStepper<Int128, kDims>(prepared).ForEachPoint(sink);
    }
    return;
  }
  AdaptiveSettings settings;
  settings.mode =
      options.mode == StepMode::kStepExact ? AdaptiveMode::kStepExact : AdaptiveMode::kTolerance;
  settings.tolerance_q8 =
      static_cast<std::uint32_t>(std::min(std::floor(tolerance_q * 256), 4294967295.0));
  PreparedAdaptiveCurve<kDims> prepared;
  const Status status = PrepareAdaptiveCurve(curve, settings, &prepared);
  if (status != Status::kOk) Refuse(options, status, where);
  const double unit = std::ldexp(1.0, -prepared.finest_level);
  const auto sink = [&](std::uint32_t position, const std::int32_t(&p)[kDims]) {
    add(position * unit, p);
  };
  if (prepared.format.acc_bits == 64) {
    AdaptiveCurveStepper<std::int64_t, kDims>(prepared).ForEachPoint(sink);
  } else {
    AdaptiveCurveStepper<Int128, kDims>(prepared).ForEachPoint(sink);
  }
}

using StrokeCubic = std::array<std::array<double, 3>, 4>;

// A cubic's Bézier control points through the output map (they are points,
// so the whole affine map), z = 0 in 2-D.
StrokeCubic MappedBezier(const std::array<Point3, 4>& power_ascending, const OutputMap& map,
                         int dims) {
  StrokeCubic out{};
  const std::array<Point3, 4> bezier = BezierFromPower(power_ascending);
  for (int k = 0; k < 4; ++k) {
    out[k] = map.Apply(bezier[k]);
    if (dims == 2) out[k][2] = 0;
  }
  return out;
}

template <int kDims>
void DrawPatch(const Patch& patch, std::size_t index, const OutputMap& map,
               const ToolpathOptions& options, std::vector<Stroke>* strokes) {
  PatchGeometry1 geometry[kDims];
  PatchToQuanta(patch, map, options.quantum, kDims, geometry);
  const PowerCoefficients exact = CoefficientsOf(patch);
  const auto draw_family = [&](IsolineFamily family, int lines) {
    if (lines == 0) return;
    IsolineWalker<kDims> walker;
    const Status created = IsolineWalker<kDims>::Create(geometry, patch.basis, family,
                                                        static_cast<std::uint16_t>(lines), &walker);
    if (created != Status::kOk) Refuse(options, created, patch.origin + ": isolines");
    PowerCurve1 curve[kDims];
    for (int i = 0; walker.Next(curve); ++i) {
      Stroke stroke;
      stroke.patch = index;
      stroke.family = family;
      stroke.line_param = LineParam(i, lines);
      StepLine(curve, options,
               patch.origin + ": " + (family == IsolineFamily::kSLines ? "s" : "t") + "-line " +
                   std::to_string(i),
               &stroke);
      // An isoline of a bicubic patch is a cubic: its exact power form, ascending.
      const auto line = LineCoefficients(exact, family, stroke.line_param);
      stroke.cubics.push_back(MappedBezier({line[3], line[2], line[1], line[0]}, map, kDims));
      // A line that collapses to a point (a pole, like the teapot lid's top) draws nothing.
      if (stroke.points.size() >= 2) strokes->push_back(std::move(stroke));
    }
  };
  draw_family(IsolineFamily::kSLines, options.lines_s);
  draw_family(IsolineFamily::kTLines, options.lines_t);
}

template <int kDims>
void DrawCurve(const Curve& curve, std::size_t index, const OutputMap& map,
               const ToolpathOptions& options, std::vector<Stroke>* strokes) {
  CurveGeometry1 geometry[kDims];
  CurveToQuanta(curve, map, options.quantum, kDims, geometry);
  PowerCurve1 power[kDims];
  const Status status = CurvePowerCoefficients(geometry, curve.basis, power);
  if (status != Status::kOk) Refuse(options, status, curve.origin);
  Stroke stroke;
  stroke.curve = static_cast<std::ptrdiff_t>(index);
  stroke.layer = curve.layer;
  const VecPoly exact = CurvePolynomial(curve);  // ascending, degree ≤ 3
  std::array<Point3, 4> ascending{};
  for (std::size_t k = 0; k < exact.size() && k < 4; ++k) ascending[k] = exact[k];
  stroke.cubics.push_back(MappedBezier(ascending, map, kDims));
  StepLine(power, options, curve.origin, &stroke);
  if (stroke.points.size() >= 2) strokes->push_back(std::move(stroke));
}

// One value in output units as engine geometry; EngineError naming `origin`
// beyond the engine's range.
GeometryFixed OutputGeometry(double value, const Quantum& quantum, const std::string& origin) {
  const std::optional<GeometryFixed> geometry = ToGeometry(value, quantum);
  if (!geometry) {
    throw EngineError(origin + ": in output space a control value reaches " + FormatNumber(value) +
                      " units, beyond ±2^31 quanta of " + quantum.Format(1) +
                      "; use a coarser quantum or a smaller page");
  }
  return *geometry;
}

}  // namespace

void PatchToQuanta(const Patch& patch, const OutputMap& map, const Quantum& quantum, int dims,
                   PatchGeometry1* geometry) {
  PatchToQuanta(patch, map, {quantum, quantum, quantum}, dims, geometry);
}

void CurveToQuanta(const Curve& curve, const OutputMap& map, const Quantum& quantum, int dims,
                   CurveGeometry1* geometry) {
  CurveToQuanta(curve, map, {quantum, quantum, quantum}, dims, geometry);
}

void PatchToQuanta(const Patch& patch, const OutputMap& map, const std::array<Quantum, 3>& quanta,
                   int dims, PatchGeometry1* geometry) {
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const auto out =
          IsPoint(patch.basis, i, j) ? map.Apply(patch.g[i][j]) : map.ApplyLinear(patch.g[i][j]);
      for (int c = 0; c < dims; ++c) {
        geometry[c].g[i][j] =
            OutputGeometry(out[c], quanta[static_cast<std::size_t>(c)], patch.origin);
      }
    }
  }
}

void CurveToQuanta(const Curve& curve, const OutputMap& map, const std::array<Quantum, 3>& quanta,
                   int dims, CurveGeometry1* geometry) {
  for (int k = 0; k < 4; ++k) {
    const auto out =
        IsCurvePoint(curve.basis, k) ? map.Apply(curve.g[k]) : map.ApplyLinear(curve.g[k]);
    for (int c = 0; c < dims; ++c) {
      geometry[c].g[k] = OutputGeometry(out[c], quanta[static_cast<std::size_t>(c)], curve.origin);
    }
  }
}

std::optional<View> NamedView(const std::string& name) {
  View v;
  v.name = name;
  if (name == "top") {
    v.right = {1, 0, 0};
    v.up = {0, 1, 0};
  } else if (name == "front") {
    v.right = {1, 0, 0};
    v.up = {0, 0, 1};
  } else if (name == "side") {
    v.right = {0, 1, 0};
    v.up = {0, 0, 1};
  } else if (name == "iso") {
    return ViewFromAngles(name, -45, std::atan(1 / std::sqrt(2.0)) * 180 / kPi);
  } else {
    return std::nullopt;
  }
  v.depth = Cross(v.right, v.up);
  return v;
}

View ViewFromAngles(const std::string& name, double azimuth_deg, double elevation_deg) {
  if (!(elevation_deg >= -90 && elevation_deg <= 90) || !std::isfinite(azimuth_deg)) {
    throw OptionError("view", "",
                      "elevation " + FormatNumber(elevation_deg) + " is outside -90..90 degrees");
  }
  const double az = azimuth_deg * kPi / 180;
  const double el = elevation_deg * kPi / 180;
  View v;
  v.name = name;
  v.depth = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  v.right = {-std::sin(az), std::cos(az), 0};
  v.up = Cross(v.depth, v.right);
  return v;
}

std::array<double, 3> OutputMap::ApplyLinear(const Point3& p) const {
  return {scale * Dot(view.right, p), scale * Dot(view.up, p), scale * Dot(view.depth, p)};
}

std::array<double, 3> OutputMap::Apply(const Point3& p) const {
  auto out = ApplyLinear(p);
  for (int c = 0; c < 3; ++c) out[c] += offset[c];
  return out;
}

namespace {

std::string PageText(const std::array<double, 2>& page) {
  return FormatNumber(page[0]) + "x" + FormatNumber(page[1]);
}

// --origin keep: no scaling, no offset in the plane (nor in depth: 3-D keeps
// the file's Z). The page is --fit's, the file's own or the drawing's far
// edge plus the margin.
void PlaceKept(const PatchSet& set, const ToolpathOptions& options, const Box& box,
               Toolpath* path) {
  const double scale = options.units_scale;
  path->map.scale = scale;
  path->map.offset = {0.0, 0.0, 0.0};
  const std::array<double, 2> lo{box.lo[0] * scale, box.lo[1] * scale};
  const std::array<double, 2> hi{box.hi[0] * scale, box.hi[1] * scale};
  if (options.fit) {
    const auto& page = *options.fit;
    // A few ulps of slack: the extent is computed, the page typed.
    const double slack = 1e-9 * std::max({page[0], page[1], 1.0});
    if (lo[0] < -slack || lo[1] < -slack || hi[0] > page[0] + slack || hi[1] > page[1] + slack) {
      throw OptionError("fit", PageText(page),
                        "is a page the drawing does not lie inside as it is (x " +
                            FormatNumber(lo[0]) + ".." + FormatNumber(hi[0]) + ", y " +
                            FormatNumber(lo[1]) + ".." + FormatNumber(hi[1]) +
                            "); --origin keep does not scale or move it: use --origin center or "
                            "min to fit it, or a larger page");
    }
    path->width = page[0];
    path->height = page[1];
  } else if (set.page) {
    path->width = (*set.page)[0] * scale;
    path->height = (*set.page)[1] * scale;
  } else {
    path->width = std::max(hi[0], 0.0) + options.margin;
    path->height = std::max(hi[1], 0.0) + options.margin;
  }
}

// --origin center or min: scaled to fit the page inside the margin (or at
// the unit factor without a page, on a page of the drawing plus margins).
void PlaceFitted(const ToolpathOptions& options, const Box& box, Toolpath* path) {
  const double bw = box.hi[0] - box.lo[0];
  const double bh = box.hi[1] - box.lo[1];
  double scale = options.units_scale;
  if (options.fit) {
    const double w = (*options.fit)[0] - 2 * options.margin;
    const double h = (*options.fit)[1] - 2 * options.margin;
    if (!(w > 0 && h > 0)) {
      throw OptionError("fit", "",
                        "the page " + PageText(*options.fit) +
                            " leaves no room inside the margin of " + FormatNumber(options.margin));
    }
    if (bw <= 0 && bh <= 0)
      throw OptionError("fit", "", "the drawing is a single point in this view");
    scale = std::min(bw > 0 ? w / bw : HUGE_VAL, bh > 0 ? h / bh : HUGE_VAL);
    path->width = (*options.fit)[0];
    path->height = (*options.fit)[1];
  } else {
    path->width = bw * scale + 2 * options.margin;
    path->height = bh * scale + 2 * options.margin;
  }
  path->map.scale = scale;
  const bool center = options.origin == PageOrigin::kCenter;
  path->map.offset = {
      (center ? (path->width - bw * scale) / 2 : options.margin) - box.lo[0] * scale,
      (center ? (path->height - bh * scale) / 2 : options.margin) - box.lo[1] * scale,
      options.dims == 3 ? -box.hi[2] * scale : 0.0};
}

}  // namespace

Toolpath PlanPage(const PatchSet& set, const ToolpathOptions& options, const std::string& units) {
  if (options.lines_s == 1 || options.lines_t == 1 || options.lines_s < 0 || options.lines_t < 0 ||
      options.lines_s > kMaxPatchSteps + 1 || options.lines_t > kMaxPatchSteps + 1) {
    throw OptionError(
        "lines", "",
        "each count must be 0 (family left out) or 2.." + std::to_string(kMaxPatchSteps + 1));
  }
  if (options.lines_s == 0 && options.lines_t == 0) {
    throw OptionError("lines", "", "both families are left out; nothing to draw");
  }
  const double needed =
      std::sqrt(static_cast<double>(options.dims)) * (0.5 + 1.0 / 1024) * options.quantum.value();
  if (!(options.tolerance > needed * 1.003)) {
    throw OptionError("tolerance", FormatNumber(options.tolerance) + " " + units,
                      "is too small: with points rounded to the quantum " +
                          options.quantum.Format(1) + " " + units + " it must exceed " +
                          FormatNumber(needed * 1.003) + " " + units + " (√" +
                          std::to_string(options.dims) + "·0.501 quanta)");
  }
  if (set.patches.empty() && set.curves.empty()) {
    throw InputError("the file has no patches or curves to draw");
  }

  Toolpath path;
  path.dims = options.dims;
  path.units = units;
  path.quantum = options.quantum;
  path.map.view = options.view;
  const Box box = DrawingBox(set, options);
  if (options.origin == PageOrigin::kKeep) {
    PlaceKept(set, options, box, &path);
  } else {
    PlaceFitted(options, box, &path);
  }
  const double scale = path.map.scale;
  path.depth = options.dims == 3 ? (box.hi[2] - box.lo[2]) * scale : 0.0;
  for (int c = 0; c < 2; ++c) {
    path.drawing_lo[c] = box.lo[c] * scale + path.map.offset[c];
    path.drawing_hi[c] = box.hi[c] * scale + path.map.offset[c];
  }
  return path;
}

Toolpath BuildToolpath(const PatchSet& set, const ToolpathOptions& options,
                       const std::string& units, const Progress& progress) {
  Toolpath path = PlanPage(set, options, units);
  path.tolerance = options.tolerance;
  path.layers = set.layers;
  for (std::size_t p = 0; p < set.patches.size(); ++p) {
    if (options.dims == 3) {
      DrawPatch<3>(set.patches[p], p, path.map, options, &path.strokes);
    } else {
      DrawPatch<2>(set.patches[p], p, path.map, options, &path.strokes);
    }
    if (progress) {
      std::size_t points = 0;
      for (const Stroke& s : path.strokes) points += s.points.size();
      progress(p + 1, set.patches.size(), points);
    }
  }
  for (std::size_t c = 0; c < set.curves.size(); ++c) {
    if (options.dims == 3) {
      DrawCurve<3>(set.curves[c], c, path.map, options, &path.strokes);
    } else {
      DrawCurve<2>(set.curves[c], c, path.map, options, &path.strokes);
    }
  }
  return path;
}

std::array<Point3, 4> BezierFromPower(const std::array<Point3, 4>& power) {
  // p(u) = Σ a_k u^k in the Bernstein basis: b0 = a0, b1 = a0 + a1/3,
  // b2 = a0 + 2a1/3 + a2/3, b3 = a0 + a1 + a2 + a3.
  std::array<Point3, 4> bezier{};
  for (int c = 0; c < 3; ++c) {
    const double a0 = power[0][c], a1 = power[1][c], a2 = power[2][c], a3 = power[3][c];
    bezier[0][c] = a0;
    bezier[1][c] = a0 + a1 / 3;
    bezier[2][c] = a0 + (2 * a1 + a2) / 3;
    bezier[3][c] = a0 + a1 + a2 + a3;
  }
  return bezier;
}

std::array<double, 3> ExactStrokePointWithDepth(const PatchSet& set, const Toolpath& path,
                                                const Stroke& stroke, double param) {
  Point3 p{};
  if (stroke.curve >= 0) {
    p = EvaluateCurve(set.curves[static_cast<std::size_t>(stroke.curve)], param);
  } else {
    const Patch& patch = set.patches[stroke.patch];
    p = stroke.family == IsolineFamily::kSLines
            ? EvaluateReference(patch, stroke.line_param, param)
            : EvaluateReference(patch, param, stroke.line_param);
  }
  return path.map.Apply(p);
}

std::array<double, 3> ExactStrokePoint(const PatchSet& set, const Toolpath& path,
                                       const Stroke& stroke, double param) {
  auto out = ExactStrokePointWithDepth(set, path, stroke, param);
  if (path.dims == 2) out[2] = 0;
  return out;
}

}  // namespace fdsurf::host
