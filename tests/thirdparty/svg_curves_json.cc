// SPDX-License-Identifier: MIT
// Prints what ReadSvg makes of an SVG file as JSON, for check_svg.py:
//   svg_curves_json FILE.svg
//   {"page": [w, h] | null, "notes": [...],
//    "curves": [{"origin": "...", "points": [[x, y], [x, y], [x, y], [x, y]]}, ...]}
// Each curve's four Bézier control points in mm, y up, as ReadSvg returns
// them (shortest round-trip decimals). Exit 1 with the reader's message on stderr.
#include <cstdio>
#include <exception>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "fdsurf/host/svg_io.h"

namespace {

nlohmann::json CurvesAsJson(const fdsurf::host::PatchSet& set) {
  nlohmann::json curves = nlohmann::json::array();
  for (const fdsurf::host::Curve& curve : set.curves) {
    if (curve.basis != fdsurf::Basis::kBezier) {
      throw std::runtime_error(curve.origin + ": not a Bézier curve");
    }
    nlohmann::json points = nlohmann::json::array();
    for (const fdsurf::host::Point3& p : curve.g) points.push_back({p[0], p[1]});
    curves.push_back({{"origin", curve.origin}, {"points", points}});
  }
  return curves;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: svg_curves_json FILE.svg\n";
    return 2;
  }
  try {
    std::ifstream in(argv[1], std::ios::binary);
    if (!in) throw std::runtime_error(std::string(argv[1]) + ": cannot open");
    std::ostringstream text;
    text << in.rdbuf();
    const fdsurf::host::PatchSet set = fdsurf::host::ReadSvg(text.str(), argv[1]);
    nlohmann::json out;
    out["page"] = set.page ? nlohmann::json{(*set.page)[0], (*set.page)[1]} : nlohmann::json();
    out["notes"] = set.notes;
    out["curves"] = CurvesAsJson(set);
    std::cout << out.dump() << '\n';
  } catch (const std::exception& error) {
    std::cerr << "svg_curves_json: " << error.what() << '\n';
    return 1;
  }
  return 0;
}
