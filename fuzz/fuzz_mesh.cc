// SPDX-License-Identifier: MIT
// libFuzzer target: the mesh readers (host::ParseObj, host::ParsePly,
// mesh_io.h) on arbitrary bytes, each input given to both. A refusal must be
// an InputError naming the file; what they accept must keep the readers'
// promises (a unit normal per vertex, triangles of three distinct vertices
// in range). A small accepted mesh then goes through the quadric Hermite
// construction as `fdsurf plot FILE.obj` sends it (construct_io.cc,
// MeshFileAsPatchSet): a refusal is a ConstructionError, the drawing's bound
// is within its tolerance, and its curves step within 0.51 quanta of the
// reference (patch_check.h).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/mesh_io.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/quadric_hermite.h"
#include "patch_check.h"

namespace {

using fdsurf::fuzz::Finding;
using fdsurf::host::Point3;
using fdsurf::host::TriangleMesh;

// Meshes with more triangles are only read: the construction's normal
// adjustment solves a system over every edge, and an input must cost little.
constexpr std::size_t kMaxBuiltTriangles = 24;
// Fewer sections than the tool's 8: the same arcs, a quarter of the work.
constexpr int kSections = 2;

bool StartsWith(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

void CheckMesh(const TriangleMesh& mesh, const std::string& name) {
  const std::size_t n = mesh.vertices.size();
  if (n == 0 || mesh.normals.size() != n) {
    Finding("vertices and normals do not match",
            std::to_string(n) + " vertices, " + std::to_string(mesh.normals.size()) + " normals");
  }
  if (mesh.triangles.empty()) Finding("a mesh without triangles was accepted", name);
  for (std::size_t v = 0; v < n; ++v) {
    const Point3& p = mesh.vertices[v];
    const Point3& g = mesh.normals[v];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      Finding("a vertex is not finite", "vertex " + std::to_string(v));
    }
    const double length = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    // !(<=) so that a NaN normal is a finding too.
    if (!(std::fabs(length - 1) <= 1e-12)) {
      Finding("a normal is not a unit vector",
              "vertex " + std::to_string(v) + ": length " + std::to_string(length));
    }
  }
  for (const auto& t : mesh.triangles) {
    for (const int k : t) {
      if (k < 0 || static_cast<std::size_t>(k) >= n) {
        Finding("a triangle's vertex index is out of range", std::to_string(k));
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      Finding("a triangle names one vertex twice",
              std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]));
    }
  }
  for (const std::string& note : mesh.notes) {
    if (!StartsWith(note, name)) Finding("a note does not name the file", note);
  }
}

// As MeshFileAsPatchSet draws it (MeshFileConstruction), with fewer sections.
void CheckConstruction(const TriangleMesh& file, const std::string& name) {
  if (file.triangles.size() > kMaxBuiltTriangles) return;
  double tolerance = 0;  // zero for a mesh of one point: the construction refuses it
  fdsurf::host::QuadricMesh mesh = fdsurf::host::MeshFileConstruction(file, &tolerance);
  mesh.sections = kSections;
  fdsurf::host::QuadricResult result;
  try {
    result = fdsurf::host::BuildQuadricMesh(mesh, tolerance, name + ": quadric-hermite");
  } catch (const fdsurf::host::ConstructionError&) {
    return;  // refused: a degenerate triangle, normals that would turn too far, ...
  } catch (const std::exception& e) {
    Finding("the construction threw something other than ConstructionError", e.what());
  }
  if (!(result.bound <= tolerance)) {
    Finding("a drawing's proven bound exceeds its tolerance",
            std::to_string(result.bound) + " > " + std::to_string(tolerance));
  }
  for (std::size_t c = 0; c < std::min(result.curves.size(), fdsurf::fuzz::kMaxChecked); ++c) {
    fdsurf::fuzz::CheckCurve(result.curves[c]);
  }
}

template <typename Parse>
void CheckReader(const std::string& bytes, const std::string& name, Parse&& parse) {
  TriangleMesh mesh;
  try {
    mesh = parse(bytes, name);
  } catch (const fdsurf::host::InputError& e) {
    // "NAME:LINE: ..." or "NAME: ELEMENT INDEX: ..." (mesh_io.h).
    if (!StartsWith(e.what(), name + ":")) Finding("a refusal does not name the file", e.what());
    return;
  } catch (const std::exception& e) {
    Finding("the reader threw something other than InputError", e.what());
  }
  CheckMesh(mesh, name);
  CheckConstruction(mesh, name);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  CheckReader(bytes, "fuzz.obj", fdsurf::host::ParseObj);
  CheckReader(bytes, "fuzz.ply", fdsurf::host::ParsePly);
  return 0;
}
