// SPDX-License-Identifier: MIT
// The occlusion query of hidden_lines.h: is a point behind some patch?
//
// Every patch is converted to Bézier form in output space (its power
// coefficients, from the reference's basis matrices, times the inverse
// Bézier matrix; then the map, which is affine, applied to the control
// points). A Bézier patch lies in the convex hull of its control points, so
// the axis-aligned box of a sub-patch's net bounds the sub-patch: a box that
// does not contain the point's (right, up), or whose nearest depth is not
// more than eps in front of it, cannot hide it. Boxes that may hide it are
// split at (1/2, 1/2) by de Casteljau; a box that lies wholly in front (or
// is small) asks Newton's method for a witness: a patch point over the same
// (right, up) that is more than eps in front. Newton alone is not trusted
// to say "visible" (it fails where a surface is seen edge-on); the
// subdivision says it, by pruning every box.
#include <algorithm>
#include <cmath>
#include <vector>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/hidden_lines.h"
#include "fdsurf/host/reference.h"
#include "fdsurf/host/text.h"

namespace fdsurf::host {
namespace {

using Vec = std::array<double, 3>;
using Net = std::array<std::array<Vec, 4>, 4>;

// Sub-patches are split until their box is this fraction of eps across at
// most; smaller than eps so that the point's own surface is always pruned.
constexpr double kLeafFraction = 0.5;
// The precomputed levels of the hierarchy: 4^3 = 64 sub-patches per patch.
constexpr int kIndexLevels = 3;
// A safety stop for the recursion (2^-40 of a patch is far below any eps).
constexpr int kMaxLevels = 40;
// Newton's residual in the drawing plane, as a fraction of eps.
constexpr double kWitnessResidual = 1e-6;

struct Box {
  Vec lo{};
  Vec hi{};
};

Box BoxOf(const Net& net) {
  Box box{net[0][0], net[0][0]};
  for (const auto& row : net) {
    for (const Vec& p : row) {
      for (int c = 0; c < 3; ++c) {
        box.lo[c] = std::min(box.lo[c], p[c]);
        box.hi[c] = std::max(box.hi[c], p[c]);
      }
    }
  }
  return box;
}

// The power-to-Bézier matrix: row k gives control point k from the
// coefficients of u³, u², u, 1 (P0 = d, P1 = d + c/3, P2 = d + 2c/3 + b/3,
// P3 = a + b + c + d).
constexpr double kPowerToBezier[4][4] = {
    {0, 0, 0, 1}, {0, 0, 1.0 / 3, 1}, {0, 1.0 / 3, 2.0 / 3, 1}, {1, 1, 1, 1}};

// The patch's Bézier net in model space; exact for kBezier, one matrix
// product in doubles for the other bases.
Net BezierNetOf(const Patch& patch) {
  if (patch.basis == Basis::kBezier) return patch.g;
  const PowerCoefficients power = CoefficientsOf(patch);
  Net net{};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) {
          const double w = kPowerToBezier[i][a] * kPowerToBezier[j][b];
          if (w == 0) continue;
          for (int c = 0; c < 3; ++c) net[i][j][c] += w * power.c[a][b][c];
        }
      }
    }
  }
  return net;
}

// Bézier basis (rows: u³, u², u, 1; columns: control points).
constexpr double kBezierToPower[4][4] = {
    {-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 3, 0, 0}, {1, 0, 0, 0}};

// A patch in output space as power coefficients, for Newton: c[a][b]
// multiplies s^(3-a)·t^(3-b).
struct PowerPatch {
  std::array<std::array<Vec, 4>, 4> c{};
};

PowerPatch PowerOf(const Net& net) {
  PowerPatch power;
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
          const double w = kBezierToPower[a][i] * kBezierToPower[b][j];
          for (int c = 0; c < 3; ++c) power.c[a][b][c] += w * net[i][j][c];
        }
      }
    }
  }
  return power;
}

struct PointAndPartials {
  Vec p{};
  Vec ds{};
  Vec dt{};
};

PointAndPartials Evaluate(const PowerPatch& power, double s, double t) {
  const double sp[4] = {s * s * s, s * s, s, 1};
  const double dsp[4] = {3 * s * s, 2 * s, 1, 0};
  const double tp[4] = {t * t * t, t * t, t, 1};
  const double dtp[4] = {3 * t * t, 2 * t, 1, 0};
  PointAndPartials out;
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      for (int c = 0; c < 3; ++c) {
        const double k = power.c[a][b][c];
        out.p[c] += k * sp[a] * tp[b];
        out.ds[c] += k * dsp[a] * tp[b];
        out.dt[c] += k * sp[a] * dtp[b];
      }
    }
  }
  return out;
}

// Newton's method on (right, up)(s, t) = target from (s, t), kept in
// [0, 1]²: true when it converges to a point more than `depth_limit` deep.
bool FindWitness(const PowerPatch& power, double s, double t, const Vec& target, double depth_limit,
                 double residual) {
  for (int iteration = 0; iteration < 12; ++iteration) {
    const PointAndPartials e = Evaluate(power, s, t);
    const double fx = e.p[0] - target[0];
    const double fy = e.p[1] - target[1];
    if (std::hypot(fx, fy) <= residual) return e.p[2] > depth_limit;
    const double det = e.ds[0] * e.dt[1] - e.dt[0] * e.ds[1];
    if (!(std::fabs(det) > 0)) return false;
    s = std::clamp(s - (fx * e.dt[1] - fy * e.dt[0]) / det, 0.0, 1.0);
    t = std::clamp(t - (e.ds[0] * fy - e.ds[1] * fx) / det, 0.0, 1.0);
  }
  return false;
}

Vec Lerp(const Vec& a, const Vec& b) {
  return {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
}

// De Casteljau at 1/2 on four points: the halves' control points.
void Halve(const std::array<Vec, 4>& p, std::array<Vec, 4>* low, std::array<Vec, 4>* high) {
  const Vec a = Lerp(p[0], p[1]);
  const Vec b = Lerp(p[1], p[2]);
  const Vec c = Lerp(p[2], p[3]);
  const Vec ab = Lerp(a, b);
  const Vec bc = Lerp(b, c);
  const Vec mid = Lerp(ab, bc);
  *low = {p[0], a, ab, mid};
  *high = {mid, bc, c, p[3]};
}

// A sub-patch: its net and its square of the patch's parameters.
struct Piece {
  Net net{};
  std::size_t patch = 0;
  double s0 = 0;
  double t0 = 0;
  double size = 1;  // parameter width along s and t
};

// The four quarters of a piece, by s half (first index) then t half.
std::array<Piece, 4> Split(const Piece& piece) {
  Net low{};
  Net high{};
  for (int j = 0; j < 4; ++j) {
    std::array<Vec, 4> column{};
    for (int i = 0; i < 4; ++i) column[i] = piece.net[i][j];
    std::array<Vec, 4> a{};
    std::array<Vec, 4> b{};
    Halve(column, &a, &b);
    for (int i = 0; i < 4; ++i) {
      low[i][j] = a[i];
      high[i][j] = b[i];
    }
  }
  std::array<Piece, 4> quarters{};
  const double half = piece.size / 2;
  int k = 0;
  for (int side = 0; side < 2; ++side) {
    const Net& net = side == 0 ? low : high;
    std::array<Vec, 4> row_low{};
    std::array<Vec, 4> row_high{};
    Piece& first = quarters[k++];
    Piece& second = quarters[k++];
    for (int i = 0; i < 4; ++i) {
      Halve(net[i], &row_low, &row_high);
      first.net[i] = row_low;
      second.net[i] = row_high;
    }
    for (Piece* q : {&first, &second}) {
      q->patch = piece.patch;
      q->size = half;
      q->s0 = piece.s0 + side * half;
    }
    first.t0 = piece.t0;
    second.t0 = piece.t0 + half;
  }
  return quarters;
}

}  // namespace

struct SurfaceOcclusion::Index {
  double eps = 0;
  double leaf = 0;
  double residual = 0;
  std::vector<PowerPatch> patches;
  std::vector<Piece> pieces;
  std::vector<Box> boxes;
  // A grid over the drawing plane; cell (i, j) lists the pieces whose box
  // meets it.
  double x0 = 0;
  double y0 = 0;
  double cell = 1;
  int nx = 1;
  int ny = 1;
  std::vector<std::vector<std::size_t>> cells;

  void Build(const PatchSet& set, const OutputMap& map);
  bool Hides(const Piece& piece, const Box& box, const Vec& point, int level,
             bool* undecided) const;
};

void SurfaceOcclusion::Index::Build(const PatchSet& set, const OutputMap& map) {
  for (std::size_t p = 0; p < set.patches.size(); ++p) {
    Piece root;
    root.patch = p;
    const Net model = BezierNetOf(set.patches[p]);
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) root.net[i][j] = map.Apply(model[i][j]);
    }
    patches.push_back(PowerOf(root.net));
    std::vector<Piece> level{root};
    for (int l = 0; l < kIndexLevels; ++l) {
      std::vector<Piece> next;
      for (const Piece& piece : level) {
        for (const Piece& q : Split(piece)) next.push_back(q);
      }
      level = std::move(next);
    }
    for (const Piece& piece : level) {
      pieces.push_back(piece);
      boxes.push_back(BoxOf(piece.net));
    }
  }
  if (pieces.empty()) return;
  Box all = boxes.front();
  for (const Box& b : boxes) {
    for (int c = 0; c < 2; ++c) {
      all.lo[c] = std::min(all.lo[c], b.lo[c]);
      all.hi[c] = std::max(all.hi[c], b.hi[c]);
    }
  }
  const double extent = std::max({all.hi[0] - all.lo[0], all.hi[1] - all.lo[1], eps});
  const int side =
      std::clamp(static_cast<int>(std::sqrt(static_cast<double>(pieces.size()))), 1, 256);
  cell = extent / side;
  x0 = all.lo[0];
  y0 = all.lo[1];
  nx = std::max(1, static_cast<int>(std::ceil((all.hi[0] - x0) / cell)));
  ny = std::max(1, static_cast<int>(std::ceil((all.hi[1] - y0) / cell)));
  cells.assign(static_cast<std::size_t>(nx) * ny, {});
  const auto clamp_cell = [](double v, int n) {
    return std::clamp(static_cast<int>(std::floor(v)), 0, n - 1);
  };
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    const int i0 = clamp_cell((boxes[k].lo[0] - x0) / cell, nx);
    const int i1 = clamp_cell((boxes[k].hi[0] - x0) / cell, nx);
    const int j0 = clamp_cell((boxes[k].lo[1] - y0) / cell, ny);
    const int j1 = clamp_cell((boxes[k].hi[1] - y0) / cell, ny);
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) cells[static_cast<std::size_t>(j) * nx + i].push_back(k);
    }
  }
}

// Whether `piece` (with its box) holds a witness that hides `point`.
bool SurfaceOcclusion::Index::Hides(const Piece& piece, const Box& box, const Vec& point, int level,
                                    bool* undecided) const {
  if (point[0] < box.lo[0] || point[0] > box.hi[0] || point[1] < box.lo[1] ||
      point[1] > box.hi[1]) {
    return false;  // the sub-patch lies beside the line of sight
  }
  const double depth_limit = point[2] + eps;
  if (box.hi[2] <= depth_limit) return false;  // nothing of it more than eps in front
  const double across =
      std::max({box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]});
  const bool small = across <= leaf || level >= kMaxLevels;
  if (box.lo[2] > depth_limit || small) {
    const double mid = piece.size / 2;
    if (FindWitness(patches[piece.patch], piece.s0 + mid, piece.t0 + mid, point, depth_limit,
                    residual)) {
      return true;
    }
  }
  if (small) {
    *undecided = true;
    return false;
  }
  for (const Piece& quarter : Split(piece)) {
    if (Hides(quarter, BoxOf(quarter.net), point, level + 1, undecided)) return true;
  }
  return false;
}

SurfaceOcclusion::SurfaceOcclusion(const PatchSet& set, const OutputMap& map, double eps)
    : index_(std::make_unique<Index>()) {
  if (!(eps > 0) || !std::isfinite(eps)) {
    throw OptionError("hidden eps", FormatNumber(eps), "must be above 0");
  }
  index_->eps = eps;
  index_->leaf = kLeafFraction * eps;
  index_->residual = kWitnessResidual * eps;
  index_->Build(set, map);
}

SurfaceOcclusion::~SurfaceOcclusion() = default;

double SurfaceOcclusion::eps() const { return index_->eps; }

SurfaceOcclusion::Answer SurfaceOcclusion::Query(const std::array<double, 3>& point) const {
  Answer answer;
  const Index& index = *index_;
  if (index.cells.empty()) return answer;
  const double fx = (point[0] - index.x0) / index.cell;
  const double fy = (point[1] - index.y0) / index.cell;
  // Outside the grid (which covers every box) nothing can hide the point.
  if (!(fx >= 0 && fx <= index.nx && fy >= 0 && fy <= index.ny)) return answer;
  const auto column = static_cast<std::size_t>(std::min(static_cast<int>(fx), index.nx - 1));
  const auto row = static_cast<std::size_t>(std::min(static_cast<int>(fy), index.ny - 1));
  const std::size_t cell = row * index.nx + column;
  for (const std::size_t k : index.cells[cell]) {
    if (index.Hides(index.pieces[k], index.boxes[k], point, kIndexLevels, &answer.undecided)) {
      answer.hidden = true;
      answer.undecided = false;
      return answer;
    }
  }
  return answer;
}

}  // namespace fdsurf::host
