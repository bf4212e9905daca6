// SPDX-License-Identifier: MIT
// Row 1 of docs/constructions.md: Hermite curves (seed 002).
#include <gtest/gtest.h>

#include "construction_test_support.h"
#include "fdsurf/host/fixed_curve.h"

namespace fdsurf::host {
namespace {

// ---- Row 1: Hermite curves (seed 002) ---------------------------------------

TEST(HermiteCurve, ReproducesTheSeedsWorkedExample) {
  // A(1,1), B(3,1), C(5,1); v = (0,1) at A, w = (0,-1) at B, s = (1,0) at C.
  const HermiteChain chain =
      MakeHermiteChain({{1, 1, 0}, {3, 1, 0}, {5, 1, 0}}, {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}},
                       {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}});
  ASSERT_EQ(chain.segments.size(), 2u);
  // The seed's product [a0 a1 a2 a3]ᵀ = M·[P0 P1 T0 T1]ᵀ with its matrix for
  // ascending powers, written out here.
  const double m[4][4] = {{1, 0, 0, 0}, {0, 0, 1, 0}, {-3, 3, -2, -1}, {2, -2, 1, 1}};
  const double gx[4] = {1, 3, 0, 0};
  const double gy[4] = {1, 1, 1, -1};
  const VecPoly p = CurvePolynomial(chain.segments[0]);
  for (int r = 0; r < 4; ++r) {
    double ax = 0;
    double ay = 0;
    for (int k = 0; k < 4; ++k) {
      ax += m[r][k] * gx[k];
      ay += m[r][k] * gy[k];
    }
    EXPECT_DOUBLE_EQ(p[r][0], ax) << r;
    EXPECT_DOUBLE_EQ(p[r][1], ay) << r;
  }
  // x(u) = 1 + 6u² − 4u³, y(u) = 1 + u − u².
  EXPECT_EQ(p[0], (Point3{1, 1, 0}));
  EXPECT_EQ(p[1], (Point3{0, 1, 0}));
  EXPECT_EQ(p[2], (Point3{6, -1, 0}));
  EXPECT_EQ(p[3], (Point3{-4, 0, 0}));
  ASSERT_EQ(chain.joins.size(), 1u);
  EXPECT_EQ(chain.joins[0], JoinClass::kParametric);
}

TEST(HermiteCurve, InterpolatesEndPointsAndEndVectors) {
  const Point3 p0{1, -2, 3};
  const Point3 p1{4, 0.5, -1};
  const Point3 t0{2, 7, -3};
  const Point3 t1{-1, 0, 5};
  const Curve c = HermiteSegment(p0, p1, t0, t1);
  EXPECT_LT(Distance(EvaluateCurve(c, 0), p0), 1e-12);
  EXPECT_LT(Distance(EvaluateCurve(c, 1), p1), 1e-12);
  const VecPoly p = CurvePolynomial(c);
  // p'(0) = a1, p'(1) = a1 + 2a2 + 3a3.
  Point3 d1{};
  for (int k = 0; k < 3; ++k) d1[k] = p[1][k] + 2 * p[2][k] + 3 * p[3][k];
  EXPECT_LT(Distance(p[1], t0), 1e-12);
  EXPECT_LT(Distance(d1, t1), 1e-12);
}

TEST(HermiteCurve, ClassifiesJoins) {
  EXPECT_EQ(ClassifyJoin({1, 2, 3}, {1, 2, 3}), JoinClass::kParametric);
  EXPECT_EQ(ClassifyJoin({1, 2, 3}, {2, 4, 6}), JoinClass::kGeometric);
  EXPECT_EQ(ClassifyJoin({1, 2, 3}, {-1, -2, -3}), JoinClass::kNotSmooth);  // opposite
  EXPECT_EQ(ClassifyJoin({1, 0, 0}, {1, 0.001, 0}), JoinClass::kNotSmooth);
  EXPECT_EQ(ClassifyJoin({0, 0, 0}, {1, 0, 0}), JoinClass::kNotSmooth);
  const HermiteChain chain = MakeHermiteChain({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}},
                                              {{1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, 0}},
                                              {{1, 0, 0}, {2, 2, 0}, {1, 0, 0}, {1, 0, 0}});
  ASSERT_EQ(chain.joins.size(), 2u);
  EXPECT_EQ(chain.joins[0], JoinClass::kGeometric);
  EXPECT_EQ(chain.joins[1], JoinClass::kNotSmooth);
  // Each segment leaves with the out vector and arrives with the in vector.
  EXPECT_EQ(chain.segments[1].g[2], (Point3{2, 2, 0}));
  EXPECT_EQ(chain.segments[1].g[3], (Point3{0, 1, 0}));
}

TEST(HermiteCurve, FixedStepperStaysWithinTheBound) {
  const Quantum q = Quantum::Parse("0.001");
  const Curve curves[] = {
      HermiteSegment({1, 1, 0}, {3, 1, 0}, {0, 1, 0}, {0, -1, 0}),
      HermiteSegment({-120.5, 33.25, 7}, {250, -80, 12.125}, {400, 300, -20}, {-50, 900, 3})};
  for (const Curve& c : curves) {
    for (int steps : {1, 7, 64, 1000, 65535}) {
      const PreparedCurve<3> prepared = PrepareFixedCurve(c, q, steps);
      double worst = 0;
      ForEachCurvePoint(prepared, [&](std::uint32_t i, const std::int32_t(&k)[3]) {
        const Point3 exact = EvaluateCurve(c, static_cast<double>(i) / steps);
        for (int a = 0; a < 3; ++a) worst = std::max(worst, std::fabs(k[a] - q.ToQuanta(exact[a])));
      });
      EXPECT_LE(worst, 0.51) << steps;
    }
  }
}

TEST(HermiteCurve, JsonChainsAndTheirErrors) {
  const PatchSet set = ReadPatchFile(FDSURF_EXAMPLES_DIR "/hermite-chain.json");
  EXPECT_TRUE(set.patches.empty());
  ASSERT_EQ(set.curves.size(), 5u);
  EXPECT_EQ(set.curves[0].g[0], (Point3{1, 1, 0}));
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"curves": [{"type": "hermite-chain", "points": [[0,0]],
                                        "vectors": [[1,0]]}]})",
                        "c.json");
            }),
            "c.json: curves[0].points: needs at least 2 points, got 1");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"curves": [{"type": "hermite-chain", "points": [[0,0],[1,0]],
                                        "vectors": [[1,0]]}]})",
                        "c.json");
            }),
            "c.json: curves[0].vectors: needs one vector per point (2)");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"curves": [{"type": "hermite", "points": [[0,0],[1,0]],
                                        "vectors": [[1,0], [1, "x"]]}]})",
                        "c.json");
            }),
            "c.json: curves[0].vectors[1][1]: must be a number");
}

}  // namespace
}  // namespace fdsurf::host
