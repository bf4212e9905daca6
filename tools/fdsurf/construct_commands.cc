// SPDX-License-Identifier: MIT
#include "construct_commands.h"

#include <cmath>
#include <cstdio>
#include <map>

#include "fdsurf/host/constructions.h"
#include "fdsurf/host/fixed_curve.h"
#include "fdsurf/host/patch_io.h"

namespace fdsurf::host {

CurveSamples::CurveSamples(const PatchSet& set, const Quantum& quantum, int steps, bool fixed)
    : set_(set), quantum_(quantum), steps_(steps), fixed_(fixed) {
  if (!fixed) return;
  for (const Curve& curve : set.curves) {
    prepared_.push_back(PrepareFixedCurve(curve, quantum, steps));
  }
}

void CurveSamples::Write(const std::function<void(const std::string&)>& out) const {
  if (set_.curves.empty()) return;
  out("curve,i,x,y,z\n");
  for (std::size_t c = 0; c < set_.curves.size(); ++c) {
    const std::string prefix = std::to_string(c) + ",";
    if (fixed_) {
      ForEachCurvePoint(prepared_[c], [&](std::uint32_t i, const std::int32_t(&q)[3]) {
        out(prefix + std::to_string(i) + "," + quantum_.Format(q[0]) + "," + quantum_.Format(q[1]) +
            "," + quantum_.Format(q[2]) + "\n");
      });
    } else {
      for (int i = 0; i <= steps_; ++i) {
        const Point3 v = EvaluateCurve(set_.curves[c], static_cast<double>(i) / steps_);
        char text[96];
        std::snprintf(text, sizeof text, "%.17g,%.17g,%.17g\n", v[0], v[1], v[2]);
        out(prefix + std::to_string(i) + "," + text);
      }
    }
  }
}

double CheckCurves(const PatchSet& set, const Quantum& quantum, int steps,
                   std::size_t* worst_curve) {
  for (const std::string& note : set.notes) std::printf("note: %s\n", note.c_str());
  if (set.curves.empty()) return 0;
  std::vector<PreparedCurve<3>> prepared;
  for (const Curve& curve : set.curves)
    prepared.push_back(PrepareFixedCurve(curve, quantum, steps));
  std::printf("curve  acc  frac  exact  max error (quanta)  at i\n");
  double worst = 0;
  for (std::size_t c = 0; c < set.curves.size(); ++c) {
    double curve_worst = 0;
    std::uint32_t at = 0;
    ForEachCurvePoint(prepared[c], [&](std::uint32_t i, const std::int32_t(&k)[3]) {
      const Point3 exact = EvaluateCurve(set.curves[c], static_cast<double>(i) / steps);
      for (int a = 0; a < 3; ++a) {
        const double error = std::fabs(k[a] - quantum.ToQuanta(exact[a]));
        if (error > curve_worst) {
          curve_worst = error;
          at = i;
        }
      }
    });
    std::printf("%5zu  %3d  %4d  %5s  %18.6f  %u\n", c, prepared[c].format.acc_bits,
                prepared[c].format.frac_bits, prepared[c].exact ? "yes" : "no", curve_worst, at);
    if (curve_worst > worst && worst_curve != nullptr) *worst_curve = c;
    worst = std::max(worst, curve_worst);
  }
  std::printf("curves: max error %.6f quanta, %zu curves (%d steps each): %s\n", worst,
              set.curves.size(), steps,
              worst <= 0.51 ? "within the 0.51-quantum bound" : "BOUND VIOLATED");
  return worst;
}

void AddJoinsOptions(CLI::App* command, JoinsOptions* options) {
  command
      ->add_option(
          "FILE", options->file,
          "drawing: patches (.bpt, .json) or a triangle mesh (.obj, .ply); see docs/formats.md")
      ->required();
  command
      ->add_option("--tolerance", options->tolerance,
                   "edge points closer than this times the geometry's size are shared")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command
      ->add_option("--angle", options->angle,
                   "largest angle (degrees) between cross legs that counts as collinear")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--ratio", options->ratio,
                   "largest relative difference of the legs' lengths that counts as equal")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

int RunJoins(const JoinsOptions& options) {
  const PatchSet set = ReadPatchFile(options.file);
  const std::vector<EdgeJoin> joins =
      CheckBezierJoins(set.patches, options.tolerance, options.angle, options.ratio);
  std::printf(
      "patch  edge  patch  edge  join        worst angle (deg)  worst |ratio-1|  "
      "degenerate rows\n");
  std::map<std::string, int> counts;
  double worst_angle = 0;
  double worst_ratio = 0;
  for (const EdgeJoin& j : joins) {
    std::printf("%5zu  %4s  %5zu  %4s  %-10s  %17.6g  %15.6g  %15d\n", j.patch_a, j.edge_a.c_str(),
                j.patch_b, j.edge_b.c_str(), j.join.c_str(), j.worst_angle_deg, j.worst_ratio_error,
                j.degenerate_rows);
    ++counts[j.join];
    worst_angle = std::max(worst_angle, j.worst_angle_deg);
    worst_ratio = std::max(worst_ratio, j.worst_ratio_error);
  }
  std::printf("%zu shared edges in %zu patches:", joins.size(), set.patches.size());
  for (const char* kind : {"C1", "G1", "C0", "degenerate"}) {
    std::printf(" %d %s%s", counts[kind], kind, kind[0] == 'd' ? "" : ",");
  }
  std::printf("; worst angle %.6g deg, worst |ratio-1| %.6g\n", worst_angle, worst_ratio);
  return 0;
}

}  // namespace fdsurf::host
