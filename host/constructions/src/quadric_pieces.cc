// SPDX-License-Identifier: MIT
#include "quadric_pieces.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/vec3.h"

namespace fdsurf::host::internal {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kEps = std::numeric_limits<double>::epsilon();

Point3 Unit(const Point3& a) { return Scale(a, 1 / Norm(a)); }

// An arc of a branch: the parameters from `lo` forward to `hi` (cyclic for a
// conic, where lo == hi is the whole conic).
struct BranchArc {
  SectionBranch branch;
  double lo = 0;
  double hi = 0;
};

// The forward span from lo to hi of a cyclic parameter (period π), in (0, π].
double ForwardSpan(double lo, double hi) {
  double span = std::fmod(hi - lo, kPi);
  if (span <= 0) span += kPi;
  return span;
}

bool WithinForward(double lo, double hi, double x, double slack) {
  if (std::fabs(ForwardSpan(lo, x) - kPi) < slack) return true;  // x at lo
  return ForwardSpan(lo, x) <= ForwardSpan(lo, hi) + slack;
}

// The parameter `fraction` of the way along an arc.
double ArcParameter(const BranchArc& a, double fraction) {
  if (!a.branch.Cyclic()) return a.lo + (a.hi - a.lo) * fraction;
  return a.lo + ForwardSpan(a.lo, a.hi) * fraction;
}

// What the drawing of one piece works with.
class PieceDrawer {
 public:
  explicit PieceDrawer(const PieceInput& in) : in_(in) {
    centroid_ = Scale(Add(Add(in.p[0], in.p[1]), in.p[2]), 1.0 / 3);
    for (int k = 0; k < 3; ++k) size_ = std::max(size_, Norm(Sub(in.p[(k + 1) % 3], in.p[k])));
    e1_ = Unit(Sub(in.p[1], in.p[0]));
    e2_ = Unit(Cross(in.n, e1_));
  }

  std::vector<QuadricArc> Draw();

 private:
  // The caller names the triangle; this names its edge by the mesh's vertices.
  FDSURF_NODISCARD std::string EdgeName(int k) const {
    return "the edge from vertex " + std::to_string(in_.vertex_ids[k]) + " to vertex " +
           std::to_string(in_.vertex_ids[(k + 1) % 3]);
  }
  FDSURF_NODISCARD bool Inside(const Point3& x, int except = -1) const {
    for (int k = 0; k < 3; ++k) {
      if (k != except && in_.planes[k].Side(x) < -1e-9 * size_) return false;
    }
    return true;
  }
  FDSURF_NODISCARD double Height(const Point3& x) const { return Dot(in_.n, Sub(x, in_.p[0])); }
  void FindOutline(int k);
  FDSURF_NODISCARD bool InsideOthers(const BranchArc& arc, int k, double* length, int* left) const;
  FDSURF_NODISCARD bool FindCorner(int k, const std::vector<SectionBranch>& branches);
  FDSURF_NODISCARD bool OnOutline(int k, const Point3& x) const;
  FDSURF_NODISCARD std::vector<SectionBranch> SectionAt(double h) const {
    return SectionOf(*in_.f, Add(centroid_, Scale(in_.n, h)), e1_, e2_, std::nullopt, reach_);
  }
  void HeightRange(double* lo, double* hi) const;
  FDSURF_NODISCARD bool OvalInside(double h) const;
  FDSURF_NODISCARD bool OvalBelongs(double h) const;
  void SectionArcs(double h, std::vector<BranchArc>* out) const;
  void Emit(const BranchArc& a, QuadricArc::Role role, int index,
            std::vector<QuadricArc>* out) const;

  const PieceInput& in_;
  Point3 centroid_{};
  Point3 e1_{};
  Point3 e2_{};
  double size_ = 0;
  double reach_ = 0;
  /// Per edge, the arcs from its first vertex to its second (one, or two
  /// segments of a pair of lines meeting at a corner).
  std::vector<std::vector<BranchArc>> outline_;
};

// Whether an arc stays inside the planes other than k (sampled), and its
// length. Else *left is the plane it leaves, or −1 where it runs through
// infinity.
bool PieceDrawer::InsideOthers(const BranchArc& arc, int k, double* length, int* left) const {
  *length = 0;
  *left = -1;
  for (double inf : arc.branch.AtInfinity()) {
    if (arc.branch.Cyclic() && ForwardSpan(arc.lo, inf) < ForwardSpan(arc.lo, arc.hi) &&
        std::fabs(ForwardSpan(arc.lo, inf) - kPi) > 1e-12) {
      return false;
    }
  }
  Point3 previous = arc.branch.At(arc.lo);
  for (int i = 1; i <= 32; ++i) {
    const Point3 x = arc.branch.At(ArcParameter(arc, i / 32.0));
    for (int j = 0; j < 3; ++j) {
      if (j != k && in_.planes[j].Side(x) < -1e-9 * size_) {
        *left = j;
        return false;
      }
    }
    *length += Norm(Sub(x, previous));
    previous = x;
  }
  return true;
}

// A degenerate glue conic, two lines: one through each vertex. The outline
// runs along them through their crossing.
bool PieceDrawer::FindCorner(int k, const std::vector<SectionBranch>& branches) {
  const Point3& a = in_.p[k];
  const Point3& b = in_.p[(k + 1) % 3];
  if (branches.size() != 2) return false;
  for (int first = 0; first < 2; ++first) {
    const SectionBranch& la = branches[first];
    const SectionBranch& lb = branches[1 - first];
    const double pa = la.ParameterOf(a);
    const double pb = lb.ParameterOf(b);
    if (Norm(Sub(la.At(pa), a)) > 1e-7 * size_ || Norm(Sub(lb.At(pb), b)) > 1e-7 * size_) continue;
    // The corner: where la meets lb, found as lb's crossing of the plane
    // through la perpendicular to the glue plane.
    const Point3 dir = Sub(la.At(pa + 1), la.At(pa));
    const Plane through_a = Plane::Through(a, Unit(Cross(dir, in_.planes[k].normal)));
    const std::vector<double> at = lb.Crossings(through_a);
    if (at.size() != 1) continue;
    const Point3 corner = lb.At(at[0]);
    const double ca = la.ParameterOf(corner);
    const BranchArc first_leg{la, std::min(pa, ca), std::max(pa, ca)};
    const BranchArc second_leg{lb, std::min(pb, at[0]), std::max(pb, at[0])};
    double la_length = 0;
    double lb_length = 0;
    int left = -1;
    if (InsideOthers(first_leg, k, &la_length, &left) &&
        InsideOthers(second_leg, k, &lb_length, &left)) {
      outline_.push_back({first_leg, second_leg});
      reach_ = std::max(reach_, 2 * (la_length + lb_length));
      return true;
    }
  }
  return false;
}

// The outline along edge k: the arc of the glue conic from p[k] to p[k+1]
// that stays inside the other two planes and does not run through infinity;
// of two such (both halves of an ellipse), the shorter.
void PieceDrawer::FindOutline(int k) {
  const Point3& a = in_.p[k];
  const Point3& b = in_.p[(k + 1) % 3];
  const Point3 along = Unit(Sub(b, a));
  const Point3 across = Unit(Cross(in_.planes[k].normal, along));
  const std::vector<SectionBranch> branches =
      SectionOf(*in_.f, a, along, across, a, Norm(Sub(b, a)));
  std::optional<BranchArc> best;
  double best_length = 0;
  int left_plane = -1;  // a finite candidate left this plane
  for (const SectionBranch& branch : branches) {
    const double pa = branch.ParameterOf(a);
    const double pb = branch.ParameterOf(b);
    if (Norm(Sub(branch.At(pa), a)) > 1e-7 * size_ || Norm(Sub(branch.At(pb), b)) > 1e-7 * size_) {
      continue;  // a line of a degenerate conic that misses a vertex
    }
    std::vector<BranchArc> candidates;
    if (branch.Cyclic()) {
      candidates = {{branch, pa, pb}, {branch, pb, pa}};
    } else {
      candidates = {{branch, std::min(pa, pb), std::max(pa, pb)}};
    }
    for (const BranchArc& c : candidates) {
      double length = 0;
      int left = -1;
      if (!InsideOthers(c, k, &length, &left)) {
        if (left >= 0) left_plane = left;
        continue;
      }
      if (!best || length < best_length) {
        best = c;
        best_length = length;
      }
    }
  }
  if (best) {
    outline_.push_back({*best});
    reach_ = std::max(reach_, 2 * best_length);
    return;
  }
  if (FindCorner(k, branches)) return;
  if (left_plane >= 0) {
    // Both trimming planes pass through the vertex they share; the curve
    // arrives there from the wrong side of the other one.
    const int vertex = left_plane == (k + 1) % 3 ? (k + 1) % 3 : k;
    throw ConstructionError(EdgeName(k) +
                            ": the quadric's curve in the edge's trimming plane leaves the "
                            "trimming plane of " +
                            EdgeName(left_plane) + " near vertex " +
                            std::to_string(in_.vertex_ids[vertex]) +
                            " (the glue planes around that vertex cross: choose a mu nearer the "
                            "normals' curvature, or refine the mesh)");
  }
  throw ConstructionError(EdgeName(k) +
                          ": the quadric's curve in the edge's trimming plane does not run from "
                          "vertex to vertex without passing through infinity (the piece is "
                          "unbounded)");
}

bool PieceDrawer::OnOutline(int k, const Point3& x) const {
  for (const BranchArc& o : outline_[k]) {
    const double p = o.branch.ParameterOf(x);
    if (Norm(Sub(o.branch.At(p), x)) > 1e-6 * size_) continue;
    if (!o.branch.Cyclic()) {
      if (p >= o.lo - 1e-9 * size_ && p <= o.hi + 1e-9 * size_) return true;
    } else if (WithinForward(o.lo, o.hi, p, 1e-9)) {
      return true;
    }
  }
  return false;
}

// Whether the section at height h is a whole ellipse strictly inside the
// three planes.
bool PieceDrawer::OvalInside(double h) const {
  const std::vector<SectionBranch> branches = SectionAt(h);
  if (branches.size() != 1 || !branches[0].Cyclic() || !branches[0].AtInfinity().empty()) {
    return false;
  }
  for (const Plane& plane : in_.planes) {
    if (!branches[0].Crossings(plane).empty()) return false;
  }
  return Inside(branches[0].At(0));
}

// An ellipse inside the planes belongs to this piece (not to another part of
// the quadric inside them) when, moved towards the triangle's plane (h = 0,
// where the section runs through the vertices), it first touches a plane at
// a point of the outline.
bool PieceDrawer::OvalBelongs(double h) const {
  double inside = h;
  double touching = 0;
  for (int i = 0; i < 60; ++i) {
    const double middle = (inside + touching) / 2;
    (OvalInside(middle) ? inside : touching) = middle;
  }
  for (const SectionBranch& branch : SectionAt(touching)) {
    for (int k = 0; k < 3; ++k) {
      for (double p : branch.Crossings(in_.planes[k])) {
        if (OnOutline(k, branch.At(p))) return true;
      }
    }
  }
  return false;
}

// The piece's extent along n: the outline's, widened to an interior extreme
// (a pole, where the tangent plane is parallel to the triangle) of the piece.
void PieceDrawer::HeightRange(double* lo, double* hi) const {
  *lo = 0;
  *hi = 0;
  for (const std::vector<BranchArc>& edge : outline_) {
    for (const BranchArc& o : edge) {
      for (int i = 0; i <= 64; ++i) {
        const double h = Height(o.branch.At(ArcParameter(o, i / 64.0)));
        *lo = std::min(*lo, h);
        *hi = std::max(*hi, h);
      }
    }
  }
  const Quadric& f = *in_.f;
  const double a = f.Form(e1_, e1_);
  const double b = f.Form(e1_, e2_);
  const double c = f.Form(e2_, e2_);
  const double det = a * c - b * b;
  if (!(det > 1e-12 * (a * a + c * c))) return;  // sections are not ellipses
  // The section's value at its centre is quadratic in h; its roots are the
  // poles' heights.
  const auto centre_value = [&](double h) {
    const Point3 o = Add(centroid_, Scale(in_.n, h));
    const Point3 d0 = Sub(o, f.p);
    const double d = f.Form(d0, e1_) + Dot(f.a, e1_);
    const double e = f.Form(d0, e2_) + Dot(f.a, e2_);
    const double u = (-d * c + e * b) / det;
    const double v = (-e * a + d * b) / det;
    return f.Value(Add(o, Add(Scale(e1_, u), Scale(e2_, v))));
  };
  const double s = size_;
  const double g0 = centre_value(0);
  const double gp = centre_value(s);
  const double gm = centre_value(-s);
  const double alpha = (gp + gm - 2 * g0) / (2 * s * s);
  const double beta = (gp - gm) / (2 * s);
  std::vector<double> roots;
  if (std::fabs(alpha) > 1e-14 * (std::fabs(beta) / s + std::fabs(g0) / (s * s))) {
    const double disc = beta * beta - 4 * alpha * g0;
    if (disc >= 0) {
      roots = {(-beta + std::sqrt(disc)) / (2 * alpha), (-beta - std::sqrt(disc)) / (2 * alpha)};
    }
  } else if (beta != 0) {
    roots = {-g0 / beta};
  }
  for (double hp : roots) {
    if (std::fabs(hp) > 64 * size_) continue;
    const double probe = hp * (1 - 1e-6);
    if (OvalInside(probe) && OvalBelongs(probe)) {
      *lo = std::min(*lo, hp);
      *hi = std::max(*hi, hp);
    }
  }
}

// The section's arcs that belong to the piece: between crossings of the
// planes that lie on the outline, or a whole ellipse that belongs.
void PieceDrawer::SectionArcs(double h, std::vector<BranchArc>* out) const {
  for (const SectionBranch& branch : SectionAt(h)) {
    struct Break {
      double p;
      int plane;  // -1: a point at infinity
    };
    std::vector<Break> breaks;
    for (double p : branch.AtInfinity()) breaks.push_back({p, -1});
    for (int k = 0; k < 3; ++k) {
      for (double p : branch.Crossings(in_.planes[k])) breaks.push_back({p, k});
    }
    if (breaks.empty()) {
      if (branch.Cyclic() && Inside(branch.At(0)) && OvalBelongs(h)) out->push_back({branch, 0, 0});
      continue;
    }
    std::sort(breaks.begin(), breaks.end(),
              [](const Break& x, const Break& y) { return x.p < y.p; });
    const std::size_t n = breaks.size();
    const std::size_t intervals = branch.Cyclic() ? n : n - 1;
    for (std::size_t i = 0; i < intervals; ++i) {
      const Break& from = breaks[i];
      const Break& to = breaks[(i + 1) % n];
      if (from.plane < 0 || to.plane < 0) continue;
      const BranchArc arc{branch, from.p, to.p};
      if (!Inside(branch.At(ArcParameter(arc, 0.5)))) continue;
      if (!OnOutline(from.plane, branch.At(from.p)) || !OnOutline(to.plane, branch.At(to.p))) {
        continue;  // another part of the quadric inside the planes
      }
      out->push_back(arc);
    }
  }
}

void PieceDrawer::Emit(const BranchArc& a, QuadricArc::Role role, int index,
                       std::vector<QuadricArc>* out) const {
  for (const RationalQuadratic& rq : a.branch.Arc(a.lo, a.hi)) {
    QuadricArc arc;
    arc.triangle = in_.triangle;
    arc.role = role;
    arc.index = index;
    arc.arc = rq;
    // Each cubic's bound includes its sub-arc's own distance from the
    // quadric (rounding, and a Lipschitz bound that needs a short arc).
    arc.cubics = ArcToCubics(rq, in_.tolerance, [&](const RationalQuadratic& piece) {
      return ArcDistanceBound(piece, *in_.f);
    });
    for (const CubicArc& cubic : arc.cubics) arc.bound = std::max(arc.bound, cubic.bound);
    out->push_back(std::move(arc));
  }
}

std::vector<QuadricArc> PieceDrawer::Draw() {
  for (int k = 0; k < 3; ++k) FindOutline(k);
  std::vector<QuadricArc> out;
  for (int k = 0; k < 3; ++k) {
    for (const BranchArc& o : outline_[k]) Emit(o, QuadricArc::Role::kOutline, k, &out);
  }
  double lo = 0;
  double hi = 0;
  HeightRange(&lo, &hi);
  if (hi - lo <= 1e-9 * size_) return out;  // a flat piece: its outline is all of it
  for (int i = 1; i <= in_.sections; ++i) {
    const double h = lo + (hi - lo) * i / (in_.sections + 1);
    std::vector<BranchArc> arcs;
    SectionArcs(h, &arcs);
    for (const BranchArc& a : arcs) Emit(a, QuadricArc::Role::kSection, i - 1, &out);
  }
  return out;
}

double Binomial(int n, int k) {
  double r = 1;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

}  // namespace

double ArcDistanceBound(const RationalQuadratic& arc, const Quadric& f) {
  // F(N/W)·W² = DᵀMD + 2(A·D)·W with D = N − P·W, a quartic in Bernstein
  // form: D_j = W_j·(p_j − P), products of quadratics combined by
  // C(2,i)·C(2,j)/C(4,i+j).
  const double weight[3] = {1, arc.w, 1};
  const Point3 d[3] = {Sub(arc.p0, f.p), Scale(Sub(arc.p1, f.p), arc.w), Sub(arc.p2, f.p)};
  double largest = 0;
  double magnitude = 0;
  for (int k = 0; k <= 4; ++k) {
    double sum = 0;
    double size = 0;
    for (int i = std::max(0, k - 2); i <= std::min(2, k); ++i) {
      const int j = k - i;
      const double factor = Binomial(2, i) * Binomial(2, j) / Binomial(4, k);
      const double quadratic = f.Form(d[i], d[j]);
      const double linear = 2 * Dot(f.a, d[i]) * weight[j];
      sum += factor * (quadratic + linear);
      size += factor * (std::fabs(quadratic) + std::fabs(linear));
    }
    largest = std::max(largest, std::fabs(sum));
    magnitude = std::max(magnitude, size);
  }
  const double least_weight = std::min(1.0, (1 + arc.w) / 2);
  const double epsilon = (largest + 32 * kEps * magnitude) / (least_weight * least_weight);
  // |∇F| on the arc, which lies in the triangle p0 p1 p2 (w > 0): at least
  // its value at the middle less 2‖M‖ times the distance to a corner.
  double m_norm = 0;
  for (const auto& row : f.m) {
    for (double v : row) m_norm += v * v;
  }
  m_norm = std::sqrt(m_norm);
  const Point3 middle = arc.At(0.5);
  const double radius =
      std::max({Norm(Sub(arc.p0, middle)), Norm(Sub(arc.p1, middle)), Norm(Sub(arc.p2, middle))});
  const double gamma = Norm(f.Gradient(middle)) * (1 - 1e-12) - 2 * m_norm * radius;
  if (!(gamma > 0) || 4 * epsilon * m_norm > gamma * gamma) {
    return std::numeric_limits<double>::infinity();
  }
  return 2 * epsilon / gamma;
}

std::vector<QuadricArc> DrawPiece(const PieceInput& in) {
  PieceDrawer drawer(in);
  return drawer.Draw();
}

}  // namespace fdsurf::host::internal
