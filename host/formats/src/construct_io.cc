// SPDX-License-Identifier: MIT
#include "construct_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>

#include "fdsurf/host/constructions.h"
#include "fdsurf/host/mesh_io.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/quadric_hermite.h"
#include "fdsurf/host/text.h"

namespace fdsurf::host {
namespace {

using nlohmann::json;

using Place = JsonPlace;

void CheckFields(const json& object, const Place& place, std::initializer_list<const char*> allowed,
                 std::initializer_list<const char*> required) {
  if (!object.is_object()) throw place.Error("must be an object");
  for (const auto& [key, unused] : object.items()) {
    bool known = false;
    std::string list;
    for (const char* name : allowed) {
      known = known || key == name;
      list += list.empty() ? "\"" : ", \"";
      list += name;
      list += '"';
    }
    if (!known) {
      std::string message = "unknown field \"" + key;
      message += "\" (expected ";
      message += list;
      message += ")";
      throw place.Error(message);
    }
  }
  for (const char* name : required) {
    if (!object.contains(name)) throw place.Error(std::string("missing \"") + name + "\"");
  }
}

double Number(const json& value, const Place& place) {
  if (!value.is_number()) throw place.Error("must be a number");
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw place.Error("must be finite");
  return v;
}

double Positive(const json& value, const Place& place) {
  const double v = Number(value, place);
  if (!(v > 0)) throw place.Error("must be positive");
  return v;
}

bool Bool(const json& value, const Place& place) {
  if (!value.is_boolean()) throw place.Error("must be true or false");
  return value.get<bool>();
}

// [x, y] (z = 0) or [x, y, z].
Point3 ParsePoint(const json& value, const Place& place) {
  if (!value.is_array() || value.size() < 2 || value.size() > 3) {
    throw place.Error("must be a point [x, y, z] (or [x, y])");
  }
  Point3 p{};
  for (std::size_t k = 0; k < value.size(); ++k) p[k] = Number(value[k], place.Index(k));
  return p;
}

std::vector<Point3> ParsePoints(const json& value, const Place& place, std::size_t min_count) {
  if (!value.is_array()) throw place.Error("must be an array of points");
  if (value.size() < min_count) {
    throw place.Error("needs at least " + std::to_string(min_count) + " points, got " +
                      std::to_string(value.size()));
  }
  std::vector<Point3> points;
  for (std::size_t k = 0; k < value.size(); ++k)
    points.push_back(ParsePoint(value[k], place.Index(k)));
  return points;
}

std::vector<double> ParseNumbers(const json& value, const Place& place) {
  if (!value.is_array()) throw place.Error("must be an array of numbers");
  std::vector<double> numbers;
  for (std::size_t k = 0; k < value.size(); ++k)
    numbers.push_back(Number(value[k], place.Index(k)));
  return numbers;
}

// {"basis": B, "points": [4 points]}: one cubic segment.
Curve ParseCubic(const json& value, const Place& place) {
  CheckFields(value, place, {"basis", "points"}, {"basis", "points"});
  Curve curve;
  curve.basis = ParseBasis(value["basis"], place.Child("basis"));
  const std::vector<Point3> points = ParsePoints(value["points"], place.Child("points"), 0);
  if (points.size() != 4) {
    throw place.Child("points").Error("a cubic needs exactly 4 points, got " +
                                      std::to_string(points.size()));
  }
  for (int k = 0; k < 4; ++k) curve.g[k] = points[k];
  curve.origin = place.file + ": " + place.path;
  return curve;
}

// Corners and edges closer than this (relative to the geometry's size) match.
constexpr double kMatchTolerance = 1e-9;

// Each segment of a piecewise curve starts where the one before it ends,
// within kMatchTolerance times the size of the curve's joints (at least 1).
void CheckSegmentsMeet(const std::vector<Curve>& segments, const Place& place) {
  double scale = 1;
  for (const Curve& c : segments) {
    for (const double u : {0.0, 1.0}) {
      for (const double x : EvaluateCurve(c, u)) scale = std::max(scale, std::fabs(x));
    }
  }
  for (std::size_t k = 1; k < segments.size(); ++k) {
    const Point3 end = EvaluateCurve(segments[k - 1], 1);
    const Point3 start = EvaluateCurve(segments[k], 0);
    const double gap = std::hypot(end[0] - start[0], end[1] - start[1], end[2] - start[2]);
    if (!(gap <= kMatchTolerance * scale)) {
      throw place.Error(place.Index(k - 1).path + " ends at " + FormatPoint(end) + " but " +
                        place.Index(k).path + " starts at " + FormatPoint(start) + ", " +
                        FormatNumber(gap, 9) + " apart (tolerance " +
                        FormatNumber(kMatchTolerance * scale, 9) +
                        "): the segments of a piecewise curve must meet");
    }
  }
}

// A cubic, or an array of cubics joined end to end (a piecewise curve).
std::vector<Curve> ParsePiecewise(const json& value, const Place& place) {
  if (value.is_object()) return {ParseCubic(value, place)};
  if (!value.is_array() || value.empty()) {
    throw place.Error(R"(must be a cubic {"basis", "points"} or a non-empty array of them)");
  }
  std::vector<Curve> segments;
  for (std::size_t k = 0; k < value.size(); ++k)
    segments.push_back(ParseCubic(value[k], place.Index(k)));
  CheckSegmentsMeet(segments, place);
  return segments;
}

// A family of piecewise curves with the same number of segments each.
std::vector<std::vector<Curve>> ParseFamily(const json& value, const Place& place,
                                            std::size_t min_count) {
  if (!value.is_array()) throw place.Error("must be an array of curves");
  if (value.size() < min_count) {
    throw place.Error("needs at least " + std::to_string(min_count) + " curves, got " +
                      std::to_string(value.size()));
  }
  std::vector<std::vector<Curve>> family;
  for (std::size_t i = 0; i < value.size(); ++i) {
    family.push_back(ParsePiecewise(value[i], place.Index(i)));
    if (family[i].size() != family[0].size()) {
      throw place.Index(i).Error("has " + std::to_string(family[i].size()) +
                                 " segments but curve 0 has " + std::to_string(family[0].size()) +
                                 " (the curves must have matching parameters)");
    }
  }
  return family;
}

double Tolerance(const json& entry, const Place& place, double fallback) {
  return entry.contains("tolerance") ? Positive(entry["tolerance"], place.Child("tolerance"))
                                     : fallback;
}

std::string SegmentOrigin(const Place& place, std::size_t segment, std::size_t segments) {
  std::string origin = place.file + ": " + place.path;
  if (segments > 1) origin += " segment " + std::to_string(segment);
  return origin;
}

// Appends a surface and notes the bound if it was approximated.
void Append(const PolySurface& surface, double tolerance, const std::string& origin,
            PatchSet* set) {
  const std::size_t before = set->patches.size();
  const double bound = AppendPatches(surface, tolerance, origin, &set->patches);
  if (set->patches.size() - before > 1 || bound > 0) {
    set->notes.push_back(origin + ": degree " + std::to_string(surface.c.size() - 1) + "x" +
                         std::to_string(surface.c[0].size() - 1) + " approximated by " +
                         std::to_string(set->patches.size() - before) +
                         " bicubic Hermite pieces within " + FormatNumber(bound, 9) +
                         " (tolerance " + FormatNumber(tolerance, 9) + ")");
  }
}

// The default tolerance of approximated constructions, in file units.
constexpr double kApproximationTolerance = 1e-6;

bool CurveIsClosed(const std::vector<Curve>& segments) {
  const Point3 a = EvaluateCurve(segments.front(), 0);
  const Point3 b = EvaluateCurve(segments.back(), 1);
  double scale = 1;
  for (double x : a) scale = std::max(scale, std::fabs(x));
  const double gap = std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
  return gap <= kMatchTolerance * scale;
}

void AddRuled(const json& e, const Place& place, PatchSet* set) {
  CheckFields(e, place, {"type", "curves"}, {"curves"});
  const auto family = ParseFamily(e["curves"], place.Child("curves"), 0);
  if (family.size() != 2) {
    throw place.Child("curves").Error("a ruled surface takes exactly 2 curves, got " +
                                      std::to_string(family.size()));
  }
  for (std::size_t k = 0; k < family[0].size(); ++k) {
    Append(RuledSurface(family[0][k], family[1][k]), 1, SegmentOrigin(place, k, family[0].size()),
           set);
  }
}

void AddBilinear(const json& e, const Place& place, PatchSet* set) {
  CheckFields(e, place, {"type", "corners"}, {"corners"});
  const auto c = ParsePoints(e["corners"], place.Child("corners"), 0);
  if (c.size() != 4) {
    throw place.Child("corners").Error("needs exactly 4 corners [P00, P10, P01, P11], got " +
                                       std::to_string(c.size()));
  }
  Append(BilinearSurface(c[0], c[1], c[2], c[3]), 1, SegmentOrigin(place, 0, 1), set);
}

void AddCoons(const json& e, const Place& place, PatchSet* set) {
  CheckFields(e, place, {"type", "boundaries", "blend", "tolerance"}, {"boundaries"});
  CoonsBlend blend = CoonsBlend::kLinear;
  if (e.contains("blend")) {
    const json& b = e["blend"];
    if (b != "linear" && b != "cubic") {
      throw place.Child("blend").Error(R"(must be "linear" or "cubic")");
    }
    blend = b == "cubic" ? CoonsBlend::kCubic : CoonsBlend::kLinear;
  }
  const Place bp = place.Child("boundaries");
  if (!e["boundaries"].is_array() || e["boundaries"].size() != 4) {
    throw bp.Error("needs exactly 4 cubic curves [r(u,0), r(u,1), r(0,v), r(1,v)]");
  }
  Curve r[4];
  for (std::size_t k = 0; k < 4; ++k) r[k] = ParseCubic(e["boundaries"][k], bp.Index(k));
  try {
    Append(CoonsPatch(r[0], r[1], r[2], r[3], blend, Tolerance(e, place, kMatchTolerance)), 1,
           SegmentOrigin(place, 0, 1), set);
  } catch (const ConstructionError& error) {
    throw bp.Error(error.what());
  }
}

void AddLagrangeGrid(const json& e, const Place& place, PatchSet* set) {
  CheckFields(e, place, {"type", "u", "v", "points", "tolerance"}, {"u", "v", "points"});
  const std::vector<double> u = ParseNumbers(e["u"], place.Child("u"));
  const std::vector<double> v = ParseNumbers(e["v"], place.Child("v"));
  const Place pp = place.Child("points");
  const json& rows = e["points"];
  if (!rows.is_array()) throw pp.Error("must be an array of rows of points");
  std::vector<std::vector<Point3>> points;
  for (std::size_t k = 0; k < rows.size(); ++k)
    points.push_back(ParsePoints(rows[k], pp.Index(k), 0));
  try {
    Append(LagrangeGrid(u, v, points), Tolerance(e, place, kApproximationTolerance),
           SegmentOrigin(place, 0, 1), set);
  } catch (const ConstructionError& error) {
    throw place.Error(error.what());
  }
}

std::vector<double> FamilyParameters(const json& e, const Place& place, std::size_t count) {
  if (!e.contains("v")) {
    std::vector<double> v(count);
    for (std::size_t i = 0; i < count; ++i) v[i] = static_cast<double>(i);
    return v;
  }
  return ParseNumbers(e["v"], place.Child("v"));
}

void AddBlendedFamily(const json& e, const Place& place, bool lagrange, PatchSet* set) {
  CheckFields(e, place, {"type", "curves", "v", "tolerance"}, {"curves"});
  if (!lagrange && e.contains("v")) {
    throw place.Error(R"(a Bézier family takes no "v": its curves are control curves)");
  }
  const auto family = ParseFamily(e["curves"], place.Child("curves"), 2);
  std::vector<Poly> blend;
  try {
    if (lagrange) {
      const std::vector<double> v = FamilyParameters(e, place, family.size());
      if (v.size() != family.size()) {
        throw ConstructionError("v has " + std::to_string(v.size()) + " values but there are " +
                                std::to_string(family.size()) + " curves");
      }
      blend = LagrangeBasis(v);
    } else {
      blend = BernsteinBasis(static_cast<int>(family.size()) - 1);
    }
    const double tolerance = Tolerance(e, place, kApproximationTolerance);
    for (std::size_t k = 0; k < family[0].size(); ++k) {
      std::vector<VecPoly> curves;
      curves.reserve(family.size());
      for (const auto& c : family) curves.push_back(CurvePolynomial(c[k]));
      Append(BlendCurves(curves, blend), tolerance, SegmentOrigin(place, k, family[0].size()), set);
    }
  } catch (const ConstructionError& error) {
    throw place.Error(error.what());
  }
}

void AddHermiteFamily(const json& e, const Place& place, PatchSet* set) {
  CheckFields(e, place, {"type", "curves", "v", "derivatives", "closed"}, {"curves"});
  const bool closed = e.contains("closed") && Bool(e["closed"], place.Child("closed"));
  const auto family = ParseFamily(e["curves"], place.Child("curves"), closed ? 3 : 2);
  std::vector<std::vector<Curve>> derivatives;
  if (e.contains("derivatives")) {
    derivatives = ParseFamily(e["derivatives"], place.Child("derivatives"), family.size());
    if (derivatives.size() != family.size() || derivatives[0].size() != family[0].size()) {
      throw place.Child("derivatives")
          .Error("needs one derivative curve r_v(u, v_i) per curve, with as many segments");
    }
  }
  const std::vector<double> v = FamilyParameters(e, place, family.size() + (closed ? 1 : 0));
  bool cyclic_u = true;
  for (const auto& c : family) cyclic_u = cyclic_u && CurveIsClosed(c);
  try {
    for (std::size_t k = 0; k < family[0].size(); ++k) {
      std::vector<VecPoly> curves;
      curves.reserve(family.size());
      for (const auto& c : family) curves.push_back(CurvePolynomial(c[k]));
      std::vector<VecPoly> d;
      if (derivatives.empty()) {
        d = EstimateFamilyDerivatives(curves, v, closed);
      } else {
        for (const auto& c : derivatives) d.push_back(CurvePolynomial(c[k]));
      }
      const std::vector<PolySurface> pieces = HermiteFamily(curves, d, v, closed);
      for (std::size_t i = 0; i < pieces.size(); ++i) {
        Append(pieces[i], 1,
               SegmentOrigin(place, k, family[0].size()) + " interval " + std::to_string(i), set);
      }
    }
  } catch (const ConstructionError& error) {
    throw place.Error(error.what());
  }
  set->notes.push_back(place.file + ": " + place.path + ": Hermite surface over " +
                       std::to_string(family.size()) + " curves, " +
                       (cyclic_u ? "cyclic in u (every curve is closed)" : "open in u") + ", " +
                       (closed ? "cyclic in v" : "open in v") + ", derivatives " +
                       (derivatives.empty() ? "estimated" : "given"));
}

std::size_t PatchIndex(const json& value, const Place& place, const PatchSet& set) {
  if (!value.is_number_integer() || value.get<long long>() < 0) {
    throw place.Error("must be a patch number (0, 1, ...)");
  }
  const auto index = value.get<unsigned long long>();
  if (index >= set.patches.size()) {
    throw place.Error("patch " + std::to_string(index) + " does not exist (there are " +
                      std::to_string(set.patches.size()) + " patches before this construction)");
  }
  return static_cast<std::size_t>(index);
}

void AddTransition(const json& e, const Place& place, PatchSet* set) {
  CheckFields(e, place, {"type", "a", "b", "ka", "kb"}, {"a", "b"});
  const std::size_t a = PatchIndex(e["a"], place.Child("a"), *set);
  const std::size_t b = PatchIndex(e["b"], place.Child("b"), *set);
  const double ka = e.contains("ka") ? Positive(e["ka"], place.Child("ka")) : 0;
  const double kb = e.contains("kb") ? Positive(e["kb"], place.Child("kb")) : 0;
  try {
    const Transition t = TransitionSurface(set->patches[a], set->patches[b], ka, kb);
    const std::string origin = SegmentOrigin(place, 0, 1);
    Append(t.surface, 1, origin, set);
    set->notes.push_back(origin + ": transition from patch " + std::to_string(a) +
                         " (t = 1) to patch " + std::to_string(b) + " (t = 0), k_a = " +
                         FormatNumber(t.k_a, 9) + ", k_b = " + FormatNumber(t.k_b, 9));
  } catch (const ConstructionError& error) {
    throw place.Error(error.what());
  }
}

void AddClosedNet(const json& e, const Place& place, PatchSet* set) {
  CheckFields(e, place, {"type", "basis", "net", "closed_s", "closed_t"}, {"basis", "net"});
  const Basis basis = ParseBasis(e["basis"], place.Child("basis"));
  const bool closed_s = e.contains("closed_s") && Bool(e["closed_s"], place.Child("closed_s"));
  const bool closed_t = e.contains("closed_t") && Bool(e["closed_t"], place.Child("closed_t"));
  const Place np = place.Child("net");
  const json& rows = e["net"];
  if (!rows.is_array() || rows.empty()) throw np.Error("must be a non-empty array of rows");
  std::vector<std::vector<Point3>> net;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    net.push_back(ParsePoints(rows[r], np.Index(r), 1));
    if (net[r].size() != net[0].size()) {
      throw np.Index(r).Error("has " + std::to_string(net[r].size()) + " points but row 0 has " +
                              std::to_string(net[0].size()));
    }
  }
  try {
    for (Patch& p :
         PeriodicNetPatches(net, basis, closed_s, closed_t, SegmentOrigin(place, 0, 1))) {
      set->patches.push_back(std::move(p));
    }
  } catch (const ConstructionError& error) {
    throw place.Error(error.what());
  }
}

// "mu": a number (every triangle), an array (one per triangle) or "normals".
void ParseMu(const json& e, const Place& place, QuadricMesh* mesh) {
  if (!e.contains("mu")) return;
  const json& mu = e["mu"];
  const Place mp = place.Child("mu");
  if (mu.is_string()) {
    if (mu.get<std::string>() != "normals")
      throw mp.Error(R"(must be a number, an array or "normals")");
    mesh->mu_from_normals = true;
  } else if (mu.is_number()) {
    mesh->mu = {mu.get<double>()};
  } else {
    mesh->mu = ParseNumbers(mu, mp);
  }
}

// Vertices, normals and triangles from the entry's own arrays.
void ParseInlineMesh(const json& e, const Place& place, QuadricMesh* mesh) {
  for (const char* key : {"vertices", "normals", "triangles"}) {
    if (!e.contains(key)) throw place.Error(std::string(R"(missing ")") + key + R"(" (or "mesh"))");
  }
  mesh->vertices = ParsePoints(e["vertices"], place.Child("vertices"), 3);
  mesh->normals = ParsePoints(e["normals"], place.Child("normals"), 3);
  const Place tp = place.Child("triangles");
  const json& triangles = e["triangles"];
  if (!triangles.is_array() || triangles.empty()) {
    throw tp.Error("must be a non-empty array of vertex index triples");
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const json& tri = triangles[t];
    if (!tri.is_array() || tri.size() != 3) throw tp.Index(t).Error("must be [i, j, k]");
    std::array<int, 3> indices{};
    for (std::size_t k = 0; k < 3; ++k) {
      if (!tri[k].is_number_integer()) throw tp.Index(t).Index(k).Error("must be a vertex index");
      indices[k] = tri[k].get<int>();
    }
    mesh->triangles.push_back(indices);
  }
}

// "mesh": an OBJ or PLY file, relative to the JSON file's folder.
void ReadMeshField(const json& e, const Place& place, QuadricMesh* mesh, PatchSet* set) {
  if (e.contains("vertices") || e.contains("normals") || e.contains("triangles")) {
    throw place.Error(R"(give "mesh" or "vertices", "normals" and "triangles", not both)");
  }
  if (!e["mesh"].is_string())
    throw place.Child("mesh").Error("must be the path of an OBJ or PLY file");
  std::filesystem::path path = e["mesh"].get<std::string>();
  if (path.is_relative()) path = std::filesystem::path(place.file).parent_path() / path;
  TriangleMesh file = ReadMeshFile(path.string());
  for (std::string& note : file.notes) set->notes.push_back(std::move(note));
  // The mesh file's own defaults (its normals rarely fit the seed's
  // conditions as they are); the tolerance, mu and free are the JSON's.
  double file_tolerance = 0;
  *mesh = MeshFileConstruction(std::move(file), &file_tolerance);
  mesh->mu_from_normals = !e.contains("mu") && !e.contains("free");
}

void AddQuadricHermite(const json& e, const Place& place, PatchSet* set) {
  CheckFields(e, place,
              {"type", "mesh", "vertices", "normals", "triangles", "free", "mu", "sections",
               "adjust_normals", "tolerance"},
              {});
  QuadricMesh mesh;
  if (e.contains("mesh")) {
    ReadMeshField(e, place, &mesh, set);
  } else {
    ParseInlineMesh(e, place, &mesh);
  }
  if (e.contains("free")) {
    const Place fp = place.Child("free");
    if (!e["free"].is_array()) throw fp.Error("must be an array with one list per triangle");
    for (std::size_t t = 0; t < e["free"].size(); ++t) {
      mesh.free.push_back(ParseNumbers(e["free"][t], fp.Index(t)));
    }
  }
  ParseMu(e, place, &mesh);
  if (e.contains("sections")) {
    if (!e["sections"].is_number_integer()) {
      throw place.Child("sections").Error("must be a whole number of sections per piece");
    }
    mesh.sections = e["sections"].get<int>();
  }
  if (e.contains("adjust_normals"))
    mesh.adjust_normals = Bool(e["adjust_normals"], place.Child("adjust_normals"));
  const double tolerance = Tolerance(e, place, 1e-3);
  try {
    QuadricResult result = BuildQuadricMesh(mesh, tolerance, SegmentOrigin(place, 0, 1));
    for (Curve& c : result.curves) set->curves.push_back(std::move(c));
    for (std::string& note : result.notes) set->notes.push_back(std::move(note));
  } catch (const ConstructionError& error) {
    throw place.Error(error.what());
  }
}

}  // namespace

QuadricMesh MeshFileConstruction(TriangleMesh file, double* tolerance) {
  QuadricMesh mesh;
  mesh.vertices = std::move(file.vertices);
  mesh.normals = std::move(file.normals);
  mesh.triangles = std::move(file.triangles);
  mesh.mu_from_normals = true;
  mesh.adjust_normals = true;
  Point3 lo = mesh.vertices.front();
  Point3 hi = lo;
  for (const Point3& v : mesh.vertices) {
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], v[c]);
      hi[c] = std::max(hi[c], v[c]);
    }
  }
  *tolerance = 1e-4 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  return mesh;
}

PatchSet MeshFileAsPatchSet(const std::string& path) {
  return MeshAsPatchSet(ReadMeshFile(path), path);
}

PatchSet MeshAsPatchSet(TriangleMesh file, const std::string& path) {
  PatchSet set;
  set.notes = std::move(file.notes);
  double tolerance = 0;
  const QuadricMesh mesh = MeshFileConstruction(std::move(file), &tolerance);
  try {
    QuadricResult result = BuildQuadricMesh(mesh, tolerance, path + ": quadric-hermite");
    set.curves = std::move(result.curves);
    for (std::string& note : result.notes) set.notes.push_back(std::move(note));
  } catch (const ConstructionError& error) {
    throw InputError(path + ": " + error.what() +
                     " (vertices and triangles are counted from 0, in file order)");
  }
  return set;
}

namespace {

std::string PolyText(const VecPoly& p, int c) {
  std::string text;
  static const char* const kPower[4] = {"", "·u", "·u²", "·u³"};
  for (int k = 0; k < 4; ++k) {
    const double v = p[k][c];
    if (text.empty()) {
      text = FormatNumber(v, 9) + kPower[k];
    } else {
      text += (v < 0 ? " - " : " + ") + FormatNumber(std::fabs(v), 9) + kPower[k];
    }
  }
  return text;
}

void NoteSegment(const Curve& curve, PatchSet* set) {
  const VecPoly p = CurvePolynomial(curve);
  set->notes.push_back(curve.origin + ": x(u) = " + PolyText(p, 0) + ", y(u) = " + PolyText(p, 1) +
                       ", z(u) = " + PolyText(p, 2));
}

void AddCurve(const json& e, const Place& place, PatchSet* set) {
  if (!e.is_object() || !e.contains("type")) throw place.Error(R"(missing "type")");
  const json& type = e["type"];
  if (type == "cubic") {
    CheckFields(e, place, {"type", "basis", "points"}, {"basis", "points"});
    json cubic = e;
    cubic.erase("type");
    set->curves.push_back(ParseCubic(cubic, place));
    NoteSegment(set->curves.back(), set);
    return;
  }
  if (type != "hermite" && type != "hermite-chain") {
    throw place.Child("type").Error(
        R"(unknown curve type (expected "cubic", "hermite" or "hermite-chain"))");
  }
  CheckFields(e, place, {"type", "points", "vectors"}, {"points", "vectors"});
  const bool segment = type == "hermite";
  const std::vector<Point3> points =
      ParsePoints(e["points"], place.Child("points"), segment ? 0 : 2);
  if (segment && points.size() != 2) {
    throw place.Child("points").Error("a hermite segment has exactly 2 points, got " +
                                      std::to_string(points.size()) + "; use hermite-chain");
  }
  const Place vp = place.Child("vectors");
  const json& vectors = e["vectors"];
  if (!vectors.is_array() || vectors.size() != points.size()) {
    throw vp.Error("needs one vector per point (" + std::to_string(points.size()) + ")");
  }
  std::vector<Point3> in(points.size());
  std::vector<Point3> out(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    const json& v = vectors[k];
    if (v.is_object()) {
      CheckFields(v, vp.Index(k), {"in", "out"}, {"in", "out"});
      in[k] = ParsePoint(v["in"], vp.Index(k).Child("in"));
      out[k] = ParsePoint(v["out"], vp.Index(k).Child("out"));
    } else {
      in[k] = out[k] = ParsePoint(v, vp.Index(k));
    }
  }
  HermiteChain chain;
  try {
    chain = MakeHermiteChain(points, in, out);
  } catch (const ConstructionError& error) {
    throw place.Error(error.what());
  }
  for (std::size_t k = 0; k < chain.segments.size(); ++k) {
    Curve& c = chain.segments[k];
    c.origin = SegmentOrigin(place, k, type == "hermite" ? 1 : 2);
    set->curves.push_back(c);
    NoteSegment(c, set);
  }
  for (std::size_t k = 0; k < chain.joins.size(); ++k) {
    const Point3& p = points[k + 1];
    set->notes.push_back(place.file + ": " + place.path + ": join " + std::to_string(k + 1) +
                         " at (" + FormatNumber(p[0], 9) + ", " + FormatNumber(p[1], 9) + ", " +
                         FormatNumber(p[2], 9) + "): " + JoinClassName(chain.joins[k]));
  }
}

}  // namespace

void AddConstructions(const json& construct, const std::string& file, PatchSet* set) {
  const Place place{file, "construct"};
  if (!construct.is_array() || construct.empty()) throw place.Error("must be a non-empty array");
  for (std::size_t i = 0; i < construct.size(); ++i) {
    const Place p = place.Index(i);
    const json& e = construct[i];
    if (!e.is_object() || !e.contains("type")) throw p.Error(R"(must be an object with a "type")");
    const json& type = e["type"];
    if (type == "ruled") {
      AddRuled(e, p, set);
    } else if (type == "bilinear") {
      AddBilinear(e, p, set);
    } else if (type == "coons") {
      AddCoons(e, p, set);
    } else if (type == "lagrange-grid") {
      AddLagrangeGrid(e, p, set);
    } else if (type == "lagrange-curves") {
      AddBlendedFamily(e, p, true, set);
    } else if (type == "bezier-curves") {
      AddBlendedFamily(e, p, false, set);
    } else if (type == "hermite-curves") {
      AddHermiteFamily(e, p, set);
    } else if (type == "transition") {
      AddTransition(e, p, set);
    } else if (type == "closed-net") {
      AddClosedNet(e, p, set);
    } else if (type == "quadric-hermite") {
      AddQuadricHermite(e, p, set);
    } else {
      throw p.Child("type").Error(
          "unknown construction (expected ruled, bilinear, coons, lagrange-grid, "
          "lagrange-curves, bezier-curves, hermite-curves, transition, closed-net or "
          "quadric-hermite)");
    }
  }
}

void AddCurves(const json& curves, const std::string& file, PatchSet* set) {
  const Place place{file, "curves"};
  if (!curves.is_array() || curves.empty()) throw place.Error("must be a non-empty array");
  for (std::size_t i = 0; i < curves.size(); ++i) AddCurve(curves[i], place.Index(i), set);
}

}  // namespace fdsurf::host
