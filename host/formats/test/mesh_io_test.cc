// SPDX-License-Identifier: MIT
// Reading triangle meshes (OBJ, ASCII and binary PLY). Every expected value
// is written by hand; the binary PLY files are packed here, byte by byte.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <set>

#include "fdsurf/host/mesh_io.h"
#include "fdsurf/host/vec3.h"
#include "format_test_support.h"

namespace fdsurf::host {
namespace {

using format_test::ErrorOf;

void ExpectNear(const Point3& got, const Point3& want, double tolerance, const std::string& what) {
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(got[k], want[k], tolerance) << what << " component " << k;
  }
}

using Triangles = std::vector<std::array<int, 3>>;

// ---- OBJ ------------------------------------------------------------------

TEST(Obj, ReadsVerticesNormalsAndTriangles) {
  const TriangleMesh mesh = ParseObj(
      "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 2\n"
      "vn 0 0 -3\nvn 0 -1 0\nvn 1 1 1\nvn -1 0 0\n"
      "f 1//1 3//1 2//1\nf 1//2 2//2 4//2\nf 2//3 3//3 4//3\n",
      "t.obj");
  ASSERT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.vertices[1], (Point3{2, 0, 0}));
  EXPECT_EQ(mesh.vertices[3], (Point3{0, 0, 2}));
  EXPECT_EQ(mesh.triangles, (Triangles{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}}));
  ASSERT_EQ(mesh.normals.size(), 4u);
  // Vertex 1 has corners naming vn 1 and 2: their normalised mean.
  const double h = 1 / std::sqrt(2.0);
  ExpectNear(mesh.normals[0], {0, -h, -h}, 1e-15, "vertex 1");
  // Vertex 2 names vn 1, 2 and 3; vertex 3 names vn 1 and 3, vertex 4 vn 2 and 3.
  const double r3 = 1 / std::sqrt(3.0);
  const Point3 mean2 = {r3, r3 - 1, r3 - 1};
  ExpectNear(mesh.normals[1], Scale(mean2, 1 / Norm(mean2)), 1e-15, "vertex 2");
  const Point3 mean3 = {r3, r3, r3 - 1};
  ExpectNear(mesh.normals[2], Scale(mean3, 1 / Norm(mean3)), 1e-15, "vertex 3");
  const Point3 mean4 = {r3, r3 - 1, r3};
  ExpectNear(mesh.normals[3], Scale(mean4, 1 / Norm(mean4)), 1e-15, "vertex 4");
  EXPECT_FALSE(mesh.normals_estimated);
  EXPECT_EQ(mesh.notes,
            (std::vector<std::string>{"t.obj: 4 vertices have corners naming different normals; "
                                      "each takes their normalised mean"}));
}

TEST(Obj, ReadsEveryCornerForm) {
  // v, v/vt, v//vn and v/vt/vn; one vn for all, so every vertex takes it.
  const TriangleMesh mesh = ParseObj(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\n"
      "f 1//1 2//1 3//1\nf 1/1/1 3/2/1 4/1/1\nf 1/2 2/1 4/2\nf 2 3 4\n",
      "t.obj");
  EXPECT_EQ(mesh.triangles, (Triangles{{0, 1, 2}, {0, 2, 3}, {0, 1, 3}, {1, 2, 3}}));
  for (const Point3& n : mesh.normals) EXPECT_EQ(n, (Point3{0, 0, 1}));
  EXPECT_TRUE(mesh.notes.empty());
}

TEST(Obj, NegativeIndicesCountBackFromTheLatest) {
  // Each face names the vertices and normal just before it; the last face
  // mixes a positive and negative indices.
  const TriangleMesh mesh = ParseObj(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf -3//-1 -2//-1 -1//-1\n"
      "v 1 1 0\nvn 0 0 2\nf -3//-1 -1//-1 -2//-2\n"
      "f 1//1 -2//-2 -3//-1\n",
      "t.obj");
  EXPECT_EQ(mesh.triangles, (Triangles{{0, 1, 2}, {1, 3, 2}, {0, 2, 1}}));
  for (const Point3& n : mesh.normals) EXPECT_EQ(n, (Point3{0, 0, 1}));
}

TEST(Obj, PositiveIndicesMayNameLaterStatements) {
  const TriangleMesh mesh =
      ParseObj("f 1//2 2//2 3//1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\n", "t.obj");
  EXPECT_EQ(mesh.triangles, (Triangles{{0, 1, 2}}));
  for (const Point3& n : mesh.normals) EXPECT_EQ(n, (Point3{0, 0, 1}));
}

TEST(Obj, FansPolygons) {
  // A convex pentagon and a quad: fans from the first corner.
  const TriangleMesh mesh = ParseObj(
      "vn 0 0 1\nv 0 0 0\nv 2 0 0\nv 3 2 0\nv 1 3 0\nv -1 2 0\nv 4 0 0\n"
      "f 1//1 2//1 3//1 4//1 5//1\nf 2//1 6//1 3//1\nf 6//1 3//1 4//1 2//1\n",
      "t.obj");
  EXPECT_EQ(mesh.triangles,
            (Triangles{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {1, 5, 2}, {5, 2, 3}, {5, 3, 1}}));
  EXPECT_EQ(mesh.notes, (std::vector<std::string>{
                            "t.obj: 2 polygons with more than 3 vertices fanned into triangles "
                            "(right for convex polygons)"}));
}

TEST(Obj, SkipsWhatCarriesNoGeometry) {
  // Groups, materials, smoothing, comments (whole-line and trailing), blank
  // lines, CRLF, w and colour values, a backslash continuation and vt.
  const std::string text =
      "# made by hand\r\nmtllib a.mtl\r\no thing\r\ng side\r\ns 1\r\nusemtl red\r\n\r\n"
      "   \t\r\nv 0 0 0 1\r\nv 1 0 0 0.5 # w is ignored\r\nv 0 1 \\\r\n 0\r\n"
      "v 0 0 1 0.5 0.5 0.5\r\nvt 0 0\r\nvt 1 0 0\r\nvn 0 0 1\r\nvn 0 1 \\\r\n  0\r\n"
      "s off\r\nf 1/1/1 2/2/1 3/1/1\r\nf 1//2 4//2 \\\r\n2//2\r\n";
  const TriangleMesh mesh = ParseObj(text, "t.obj");
  ASSERT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.vertices[2], (Point3{0, 1, 0}));
  EXPECT_EQ(mesh.vertices[3], (Point3{0, 0, 1}));
  EXPECT_EQ(mesh.triangles, (Triangles{{0, 1, 2}, {0, 3, 1}}));
  EXPECT_EQ(mesh.normals[2], (Point3{0, 0, 1}));
  EXPECT_EQ(mesh.normals[3], (Point3{0, 1, 0}));
  EXPECT_EQ(mesh.notes, (std::vector<std::string>{
                            "t.obj: 2 vertices have corners naming different normals; each "
                            "takes their normalised mean"}));
  const double h = 1 / std::sqrt(2.0);
  ExpectNear(mesh.normals[0], {0, h, h}, 1e-15, "vertex 1");
}

TEST(Obj, NotesPointsLinesAndUnknownStatements) {
  const TriangleMesh mesh = ParseObj(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\np 1\nl 1 2 3\nfoo 1 2\nbar\n"
      "f 1//1 2//1 3//1\n",
      "t.obj");
  EXPECT_EQ(mesh.triangles, (Triangles{{0, 1, 2}}));
  EXPECT_EQ(mesh.notes,
            (std::vector<std::string>{
                "t.obj: 2 point and line statements (p, l) skipped: they are not surfaces",
                "t.obj: 2 unknown statements skipped (the first, 'foo', on line 7)"}));
}

TEST(Obj, RefusesFreeFormGeometry) {
  EXPECT_EQ(ErrorOf([] {
              ParseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ncstype bspline\ndeg 2\n", "t.obj");
            }),
            "t.obj:5: free-form geometry 'cstype' is not supported: only polygonal faces (f) are "
            "read");
  EXPECT_EQ(ErrorOf([] { ParseObj("v 0 0 0\nsurf 0 1 0 1 1\n", "t.obj"); }),
            "t.obj:2: free-form geometry 'surf' is not supported: only polygonal faces (f) are "
            "read");
}

// A cube [-1,1]^3 as six quads, counter-clockwise from outside. Each quad
// starts at one of the corners 1, 3, 6, 8 (an even number of +1
// coordinates), so its fan diagonal joins two of them: each of these corners
// is in both triangles of each of its faces, each other corner in one, so
// every corner takes the same weight from its three faces and its estimated
// normal is the diagonal (±1,±1,±1)/√3. (Fanned from other corners, a cube's
// estimated corner normals lean towards the faces that give it two
// triangles.)
constexpr const char* kCubeVertices =
    "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n";

void ExpectCubeCornerNormals(const TriangleMesh& mesh) {
  ASSERT_EQ(mesh.normals.size(), 8u);
  const double r = 1 / std::sqrt(3.0);
  for (std::size_t i = 0; i < 8; ++i) {
    ExpectNear(mesh.normals[i], Scale(mesh.vertices[i], r), 1e-15, "corner " + std::to_string(i));
  }
}

TEST(Obj, EstimatesAreaWeightedNormalsOnACube) {
  const TriangleMesh mesh = ParseObj(std::string(kCubeVertices) +
                                         "f 1 4 3 2\nf 6 7 8 5\nf 1 2 6 5\n"
                                         "f 3 4 8 7\nf 1 5 8 4\nf 3 7 6 2\n",
                                     "cube.obj");
  EXPECT_EQ(mesh.triangles.size(), 12u);
  EXPECT_EQ(mesh.triangles[0], (std::array<int, 3>{0, 3, 2}));
  EXPECT_EQ(mesh.triangles[1], (std::array<int, 3>{0, 2, 1}));
  ExpectCubeCornerNormals(mesh);
  EXPECT_TRUE(mesh.normals_estimated);
  EXPECT_EQ(mesh.notes,
            (std::vector<std::string>{
                "cube.obj: no vertex normals; estimated (area-weighted)",
                "cube.obj: 6 polygons with more than 3 vertices fanned into triangles (right for "
                "convex polygons)"}));
}

TEST(Obj, AveragesPerFaceNormalsOnACube) {
  // The usual hard-edged export: each face names its own normal, so each
  // corner names three, whose mean is the diagonal.
  const TriangleMesh mesh =
      ParseObj(std::string(kCubeVertices) +
                   "vn 0 0 -1\nvn 0 0 1\nvn 0 -1 0\nvn 0 1 0\nvn -1 0 0\nvn 1 0 0\n"
                   "f 1//1 4//1 3//1 2//1\nf 6//2 7//2 8//2 5//2\nf 1//3 2//3 6//3 5//3\n"
                   "f 3//4 4//4 8//4 7//4\nf 1//5 5//5 8//5 4//5\nf 3//6 7//6 6//6 2//6\n",
               "cube.obj");
  ExpectCubeCornerNormals(mesh);
  EXPECT_FALSE(mesh.normals_estimated);
  EXPECT_EQ(mesh.notes[0],
            "cube.obj: 8 vertices have corners naming different normals; each takes their "
            "normalised mean");
}

TEST(Obj, EstimatesOnlyTheVerticesWhoseFacesNameNoNormal) {
  // A triangle of the plane z = 0 with a normal, and one in the plane x = 1
  // without: vertex 4 is only in the second, whose cross product is
  // (0,1,0) x (0,1,1) = (1,0,0).
  const TriangleMesh mesh = ParseObj(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 1 1 1\nvn 0 0 5\n"
      "f 1//1 2//1 3//1\nf 2 3 4\n",
      "t.obj");
  EXPECT_EQ(mesh.normals[0], (Point3{0, 0, 1}));
  EXPECT_EQ(mesh.normals[1], (Point3{0, 0, 1}));
  EXPECT_EQ(mesh.normals[2], (Point3{0, 0, 1}));
  EXPECT_EQ(mesh.normals[3], (Point3{1, 0, 0}));
  EXPECT_FALSE(mesh.normals_estimated);
  EXPECT_EQ(mesh.notes,
            (std::vector<std::string>{"t.obj: 1 of 4 vertices have no normal (their faces name "
                                      "none); estimated (area-weighted)"}));
}

TEST(Obj, RefusesMalformedInputNamingTheLine) {
  const auto error = [](const std::string& text) {
    return ErrorOf([&] { ParseObj(text, "o.obj"); });
  };
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_EQ(error("v 1 2\n"), "o.obj:1: v: missing z");
  EXPECT_EQ(error("v\n"), "o.obj:1: v: missing x");
  EXPECT_EQ(error("\n\nv 1 x 3\n"), "o.obj:3: v: y 'x' is not a number");
  EXPECT_EQ(error("v 1 2 3x\n"), "o.obj:1: v: z '3x' is not a number");
  EXPECT_EQ(error("v 1 2 3 4 5\n"),
            "o.obj:1: v: 5 numbers (expected x y z, x y z w or x y z r g b)");
  EXPECT_EQ(error("v 1e999 0 0\n"), "o.obj:1: v: x '1e999' is out of range");
  EXPECT_EQ(error("v inf 0 0\n"), "o.obj:1: v: x 'inf' is not finite");
  EXPECT_EQ(error("v 0 nan 0\n"), "o.obj:1: v: y 'nan' is not finite");
  EXPECT_EQ(error("v 0 0 0 1 2 x\n"), "o.obj:1: v: b 'x' is not a number");
  // A continued statement is named by the line it starts on.
  EXPECT_EQ(error("v 1 \\\n x 3\n"), "o.obj:1: v: y 'x' is not a number");
  EXPECT_EQ(error(tri + "vn 0 0 0\n"), "o.obj:4: vn: zero-length normal");
  EXPECT_EQ(error(tri + "vn 0 1\n"), "o.obj:4: vn: missing k");
  EXPECT_EQ(error(tri + "vn 0 1 0 1\n"), "o.obj:4: vn: 4 numbers (expected i j k)");
  EXPECT_EQ(error(tri + "vn 0 - 0\n"), "o.obj:4: vn: j '-' is not a number");
  EXPECT_EQ(error(tri + "f 1 2\n"), "o.obj:4: f needs at least 3 vertices, found 2");
  EXPECT_EQ(error(tri + "f 1 2 0\n"),
            "o.obj:4: f: '0': vertex index 0 (indices start at 1, or count back from -1 for "
            "the latest)");
  EXPECT_EQ(error(tri + "f 1 2 9\n"),
            "o.obj:4: f: '9': vertex index 9 out of range (the file has 3 vertices)");
  EXPECT_EQ(error(tri + "f -4 -2 -1\n"),
            "o.obj:4: f: '-4': vertex index -4 out of range (3 vertices before this line)");
  EXPECT_EQ(error(tri + "vn 0 0 1\nf 1//1 2//2 3//1\n"),
            "o.obj:5: f: '2//2': normal index 2 out of range (the file has 1 normal)");
  EXPECT_EQ(error(tri + "vn 0 0 1\nf 1//1 2//-2 3//1\n"),
            "o.obj:5: f: '2//-2': normal index -2 out of range (1 normal before this line)");
  EXPECT_EQ(error(tri + "vt 0 0\nf 1/1 2/2 3/1\n"),
            "o.obj:5: f: '2/2': texture coordinate index 2 out of range (the file has 1 "
            "texture coordinate)");
  for (const std::string corner : {"1/x", "1/", "1//", "/1", "1/1/1/1", "x", "1.5", "+1"}) {
    EXPECT_EQ(error(tri + "vt 0 0\nvn 0 0 1\nf " + corner + " 2 3\n"),
              "o.obj:6: f: corner '" + corner +
                  "' is not a vertex reference (v, v/vt, v//vn or v/vt/vn)");
  }
  EXPECT_EQ(error(tri + "f 1 2 1\n"), "o.obj:4: f: vertex 1 is named twice");
  EXPECT_EQ(error(tri + "f 1 2 3 -3\n"), "o.obj:4: f: vertex 1 is named twice");
  EXPECT_EQ(error(tri), "o.obj: no faces (f) in the file");
  EXPECT_EQ(error(""), "o.obj: no faces (f) in the file");
  // Vertices whose normal is to be estimated but cannot be.
  EXPECT_EQ(error(tri + "v 5 5 5\nf 1 2 3\n"),
            "o.obj:4: vertex 4 is in no face, so its normal cannot be estimated");
  EXPECT_EQ(error("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
            "o.obj:1: vertex 1: the cross products of its faces sum to zero (no area, or they "
            "cancel), so its normal cannot be estimated");
  EXPECT_EQ(error(tri + "f 1 2 3\nf 1 3 2\n"),
            "o.obj:1: vertex 1: the cross products of its faces sum to zero (no area, or they "
            "cancel), so its normal cannot be estimated");
  EXPECT_EQ(error(tri + "vn 0 0 1\nvn 0 0 -1\nf 1//1 2//1 3//1\nf 1//2 3//2 2//2\n"),
            "o.obj:1: vertex 1: its corners name normals that cancel (their mean is zero)");
}

// ---- PLY ------------------------------------------------------------------

// A square pyramid whose base quad faces -z, in an awkward layout: the vertex
// properties out of order and of several types, a list among them, normals
// not of unit length, an edge element between the vertices and the faces, a
// face property before the indices and a list after them.
constexpr const char* kPyramidHeader =
    "element vertex 5\n"
    "property float y\nproperty uchar red\nproperty double x\nproperty float z\n"
    "property list uchar float extra\n"
    "property float nx\nproperty float ny\nproperty float nz\n"
    "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
    "element face 5\nproperty uchar flags\nproperty list uchar int vertex_indices\n"
    "property list ushort uint other\n"
    "element material 0\nproperty list uchar uchar name\n"
    "end_header\n";

std::string AsciiPyramid() {
  return std::string("ply\nformat ascii 1.0\ncomment made by hand\nobj_info a pyramid\n") +
         kPyramidHeader +
         "0 255 0 0 2 0.5 0.25 0 0 2\n"
         "0 1 2 0 0 3 4 0\n"
         "2 2 2 0 1 -1e0 0 -1 0\n"
         "\n"
         "2 3 0 0 0 -1 -1 -1\n"
         "1 4 1.1 2 0 0 0 +1\n"
         "0 4\n"
         "0 4 0 3 2 1 0\n"
         "1 3 0 1 4 1 7\n"
         "2 3 1 2 4 2 7 8\n"
         "3 3 2 3 4 0\n"
         "4 3 3 0 4 0\n";
}

// Appends `bits` as `size` bytes in the chosen byte order.
void Pack(std::string* out, std::uint64_t bits, int size, bool big) {
  for (int i = 0; i < size; ++i) {
    const int shift = 8 * (big ? size - 1 - i : i);
    out->push_back(static_cast<char>((bits >> shift) & 0xff));
  }
}
void PackFloat(std::string* out, float v, bool big) {
  Pack(out, std::bit_cast<std::uint32_t>(v), 4, big);
}
void PackDouble(std::string* out, double v, bool big) {
  Pack(out, std::bit_cast<std::uint64_t>(v), 8, big);
}

struct PyramidFace {
  std::vector<std::uint32_t> indices;
  std::vector<std::uint32_t> other;
};

const std::vector<PyramidFace> kPyramidFaces = {
    {{0, 3, 2, 1}, {}}, {{0, 1, 4}, {7}}, {{1, 2, 4}, {7, 8}}, {{2, 3, 4}, {}}, {{3, 0, 4}, {}}};

// The same pyramid as AsciiPyramid(), packed.
std::string BinaryPyramid(bool big, const std::vector<PyramidFace>& faces = kPyramidFaces) {
  std::string out = std::string("ply\nformat ") +
                    (big ? "binary_big_endian" : "binary_little_endian") + " 1.0\n" +
                    kPyramidHeader;
  struct Vertex {
    float y;
    std::uint8_t red;
    double x;
    float z;
    std::vector<float> extra;
    float n[3];
  };
  const Vertex vertices[5] = {{0, 255, 0, 0, {0.5F, 0.25F}, {0, 0, 2}},
                              {0, 1, 2, 0, {}, {3, 4, 0}},
                              {2, 2, 2, 0, {-1}, {0, -1, 0}},
                              {2, 3, 0, 0, {}, {-1, -1, -1}},
                              {1, 4, 1.1, 2, {}, {0, 0, 1}}};
  for (const Vertex& v : vertices) {
    PackFloat(&out, v.y, big);
    Pack(&out, v.red, 1, big);
    PackDouble(&out, v.x, big);
    PackFloat(&out, v.z, big);
    Pack(&out, v.extra.size(), 1, big);
    for (const float e : v.extra) PackFloat(&out, e, big);
    for (const float n : v.n) PackFloat(&out, n, big);
  }
  Pack(&out, 0, 4, big);  // the edge
  Pack(&out, 4, 4, big);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    Pack(&out, f, 1, big);
    Pack(&out, faces[f].indices.size(), 1, big);
    for (const std::uint32_t i : faces[f].indices) Pack(&out, i, 4, big);
    Pack(&out, faces[f].other.size(), 2, big);
    for (const std::uint32_t o : faces[f].other) Pack(&out, o, 4, big);
  }
  return out;
}

TEST(Ply, TheTestsPackingIsRight) {
  std::string big;
  PackFloat(&big, 2.0F, true);
  EXPECT_EQ(big, std::string("\x40\x00\x00\x00", 4));
  std::string little;
  PackDouble(&little, 1.0, false);
  EXPECT_EQ(little, std::string("\x00\x00\x00\x00\x00\x00\xf0\x3f", 8));
  std::string ushort;
  Pack(&ushort, 0x0102, 2, true);
  EXPECT_EQ(ushort, "\x01\x02");
}

void ExpectPyramid(const TriangleMesh& mesh) {
  EXPECT_EQ(mesh.vertices,
            (std::vector<Point3>{{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {1.1, 1, 2}}));
  EXPECT_EQ(mesh.triangles,
            (Triangles{{0, 3, 2}, {0, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}}));
  ASSERT_EQ(mesh.normals.size(), 5u);
  const double r = 1 / std::sqrt(3.0);
  const std::vector<Point3> normals = {
      {0, 0, 1}, {0.6, 0.8, 0}, {0, -1, 0}, {-r, -r, -r}, {0, 0, 1}};
  for (std::size_t i = 0; i < 5; ++i) {
    ExpectNear(mesh.normals[i], normals[i], 1e-15, "vertex " + std::to_string(i));
  }
  EXPECT_FALSE(mesh.normals_estimated);
  EXPECT_EQ(mesh.notes, (std::vector<std::string>{
                            "m.ply: 1 polygon with more than 3 vertices fanned into triangles "
                            "(right for convex polygons)"}));
}

TEST(Ply, ReadsAsciiSkippingWhatItDoesNotNeed) { ExpectPyramid(ParsePly(AsciiPyramid(), "m.ply")); }

TEST(Ply, BinaryOfBothByteOrdersGivesTheSameMeshAsAscii) {
  const TriangleMesh ascii = ParsePly(AsciiPyramid(), "m.ply");
  const TriangleMesh little = ParsePly(BinaryPyramid(false), "m.ply");
  const TriangleMesh big = ParsePly(BinaryPyramid(true), "m.ply");
  ExpectPyramid(little);
  ExpectPyramid(big);
  EXPECT_EQ(little.vertices, ascii.vertices);
  EXPECT_EQ(little.normals, ascii.normals);
  EXPECT_EQ(little.triangles, ascii.triangles);
  EXPECT_EQ(little.notes, ascii.notes);
  EXPECT_EQ(big.vertices, ascii.vertices);
  EXPECT_EQ(big.normals, ascii.normals);
  EXPECT_EQ(big.triangles, ascii.triangles);
}

TEST(Ply, AcceptsCrlfAndTheSizedTypeNames) {
  std::string text =
      "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float32 x\r\n"
      "property float64 y\r\nproperty int16 z\r\nelement face 1\r\n"
      "property list uint8 int32 vertex_index\r\nend_header\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n"
      "3 0 1 2\r\n";
  const TriangleMesh mesh = ParsePly(text, "m.ply");
  EXPECT_EQ(mesh.vertices, (std::vector<Point3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  EXPECT_EQ(mesh.triangles, (Triangles{{0, 1, 2}}));
  for (const Point3& n : mesh.normals) EXPECT_EQ(n, (Point3{0, 0, 1}));
  EXPECT_TRUE(mesh.normals_estimated);
  EXPECT_EQ(mesh.notes,
            (std::vector<std::string>{"m.ply: no vertex normals; estimated (area-weighted)"}));
}

TEST(Ply, EstimatesAreaWeightedNormalsOnACube) {
  // The cube of the OBJ test, 0-based, its quads starting at even corners.
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 8\nproperty double x\nproperty double y\n"
      "property double z\nelement face 6\nproperty list uchar uint vertex_indices\nend_header\n"
      "-1 -1 -1\n1 -1 -1\n1 1 -1\n-1 1 -1\n-1 -1 1\n1 -1 1\n1 1 1\n-1 1 1\n"
      "4 0 3 2 1\n4 5 6 7 4\n4 0 1 5 4\n4 2 3 7 6\n4 0 4 7 3\n4 2 6 5 1\n";
  const TriangleMesh mesh = ParsePly(text, "cube.ply");
  ExpectCubeCornerNormals(mesh);
  EXPECT_TRUE(mesh.normals_estimated);
}

TEST(Ply, AVertexInNoFaceIsKeptWhenTheFileGivesItsNormal) {
  const TriangleMesh mesh = ParsePly(
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n5 5 5 1 0 0\n3 0 1 2\n",
      "m.ply");
  EXPECT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.normals[3], (Point3{1, 0, 0}));
  EXPECT_TRUE(mesh.notes.empty());
}

std::string PlyError(const std::string& bytes) {
  return ErrorOf([&] { ParsePly(bytes, "m.ply"); });
}

TEST(Ply, RefusesMalformedHeadersNamingTheLine) {
  const std::string start = "ply\nformat ascii 1.0\n";
  const std::string vertex =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string face = "element face 1\nproperty list uchar int vertex_indices\n";
  EXPECT_EQ(PlyError("solid\n"), "m.ply:1: not a PLY file (the first line is not 'ply')");
  EXPECT_EQ(PlyError(""), "m.ply:1: not a PLY file (the first line is not 'ply')");
  EXPECT_EQ(PlyError(start), "m.ply:2: the header has no end_header");
  EXPECT_EQ(PlyError("ply\nformat binary 1.0\n"),
            "m.ply:2: unknown format 'binary' (expected ascii, binary_little_endian or "
            "binary_big_endian)");
  EXPECT_EQ(PlyError("ply\nformat ascii 2.0\n"),
            "m.ply:2: unsupported version '2.0' (expected 1.0)");
  EXPECT_EQ(PlyError("ply\nformat ascii\n"),
            "m.ply:2: format takes a format and a version: 'format ascii 1.0'");
  EXPECT_EQ(PlyError(start + "format ascii 1.0\n"), "m.ply:3: a second format line");
  EXPECT_EQ(PlyError("ply\n" + vertex + face + "end_header\n"),
            "m.ply:8: no format line before end_header");
  EXPECT_EQ(PlyError(start + "property float x\n"), "m.ply:3: property before any element");
  EXPECT_EQ(PlyError(start + "element vertex x\n"),
            "m.ply:3: element vertex: count 'x' is not a whole number");
  EXPECT_EQ(PlyError(start + "element vertex -1\n"),
            "m.ply:3: element vertex: count '-1' is not a whole number");
  EXPECT_EQ(PlyError(start + "element vertex\n"),
            "m.ply:3: element takes a name and a count: 'element vertex 8'");
  EXPECT_EQ(PlyError(start + vertex + "element vertex 2\n"), "m.ply:7: a second element vertex");
  EXPECT_EQ(PlyError(start + "element vertex 3\nproperty real x\n"),
            "m.ply:4: unknown type 'real' (expected char, uchar, short, ushort, int, uint, "
            "float, double or their int8 ... float64 names)");
  EXPECT_EQ(PlyError(start + "element vertex 3\nproperty float x\nproperty double x\n"),
            "m.ply:5: a second property x in element vertex");
  EXPECT_EQ(PlyError(start + "element face 3\nproperty list float int vertex_indices\n"),
            "m.ply:4: the count type of a list must be an integer type, not float");
  EXPECT_EQ(PlyError(start + "element face 3\nproperty list uchar\n"),
            "m.ply:4: property takes a type and a name ('property float x') or 'list', two "
            "types and a name ('property list uchar int vertex_indices')");
  EXPECT_EQ(PlyError(start + "foo bar\n"), "m.ply:3: unknown header line starting 'foo'");
  EXPECT_EQ(PlyError(start + "end_header now\n"),
            "m.ply:3: unknown header line starting 'end_header'");
  // What the mesh needs.
  EXPECT_EQ(PlyError(start + face + "end_header\n"), "m.ply:5: the header has no element vertex");
  EXPECT_EQ(PlyError(start + vertex + "end_header\n"), "m.ply:7: the header has no element face");
  EXPECT_EQ(PlyError(start + "element vertex 3\nproperty float x\nproperty float y\n" + face +
                     "end_header\n"),
            "m.ply:3: element vertex has no property z");
  EXPECT_EQ(
      PlyError(start + vertex + "property float nx\nproperty float nz\n" + face + "end_header\n"),
      "m.ply:3: element vertex has only some of nx ny nz (give all three or none)");
  EXPECT_EQ(PlyError(start +
                     "element vertex 3\nproperty float x\nproperty list uchar float y\n"
                     "property float z\n" +
                     face + "end_header\n"),
            "m.ply:5: property y of element vertex must be a scalar");
  EXPECT_EQ(PlyError(start + vertex +
                     "element face 1\nproperty list uchar int indices\n"
                     "end_header\n"),
            "m.ply:7: element face has no list property vertex_indices (or vertex_index)");
  EXPECT_EQ(PlyError(start + vertex + "element face 1\nproperty int vertex_indices\nend_header\n"),
            "m.ply:8: property vertex_indices of element face must be a list");
  EXPECT_EQ(PlyError(start + vertex +
                     "element face 1\nproperty list uchar float vertex_indices\nend_header\n"),
            "m.ply:8: the entries of vertex_indices must be of an integer type, not float");
  EXPECT_EQ(PlyError(start + vertex + face + "property list uchar int vertex_index\nend_header\n"),
            "m.ply:7: element face has both vertex_indices and vertex_index");
  EXPECT_EQ(PlyError(start + vertex +
                     "element face 0\nproperty list uchar int vertex_indices\n"
                     "end_header\n"),
            "m.ply:7: element face has no faces (count 0)");
}

TEST(Ply, RefusesMalformedAsciiNamingTheLineAndTheElement) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  // Lines 13..16 are the vertices, 17 and 18 the faces.
  const std::string v = "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n";
  const std::string f = "3 0 1 2\n3 0 2 3\n";
  EXPECT_EQ(PlyError(head + v + f), "(no error)");
  const auto with_line = [&](int line, const std::string& text) {
    std::string all = v + f;
    std::size_t pos = 0;
    for (int l = 13; l < line; ++l) pos = all.find('\n', pos) + 1;
    all.replace(pos, all.find('\n', pos) - pos, text);
    return PlyError(head + all);
  };
  EXPECT_EQ(with_line(14, "1 1x 0 0 0 1"), "m.ply:14: vertex 1: y '1x' is not a number");
  EXPECT_EQ(with_line(14, "nan 0 0 0 0 1"), "m.ply:14: vertex 1: x 'nan' is not finite");
  EXPECT_EQ(with_line(14, "1e999 0 0 0 0 1"), "m.ply:14: vertex 1: x '1e999' is out of range");
  EXPECT_EQ(with_line(14, "1 0 0 0 0"), "m.ply:14: vertex 1: the line ends where nz was expected");
  EXPECT_EQ(with_line(14, "1 0 0 0 0 1 7"),
            "m.ply:14: vertex 1: unexpected value '7' after the last property");
  EXPECT_EQ(with_line(15, "1 1 0 0 0 0"), "m.ply:15: vertex 2: zero-length normal (nx ny nz)");
  EXPECT_EQ(with_line(18, "3 0 2 99"),
            "m.ply:18: face 1: vertex index 99 out of range (the file has 4 vertices)");
  EXPECT_EQ(with_line(18, "3 0 -1 3"),
            "m.ply:18: face 1: vertex index -1 out of range (the file has 4 vertices)");
  EXPECT_EQ(with_line(18, "2 0 2"), "m.ply:18: face 1: 2 vertices (a face needs at least 3)");
  EXPECT_EQ(with_line(18, "3 0 2 2"), "m.ply:18: face 1: vertex 2 is named twice");
  EXPECT_EQ(with_line(18, "3.5 0 2 3"),
            "m.ply:18: face 1: vertex_indices count '3.5' is not a whole number");
  EXPECT_EQ(with_line(18, "300 0 2 3"),
            "m.ply:18: face 1: vertex_indices count '300' is out of range for uchar");
  EXPECT_EQ(with_line(18, "3 0 2.0 3"),
            "m.ply:18: face 1: vertex_indices entry '2.0' is not a whole number");
  EXPECT_EQ(with_line(18, "4 0 2 3"),
            "m.ply:18: face 1: the line ends where vertex_indices entry was expected");
  EXPECT_EQ(PlyError(head + v + "3 0 1 2\n"),
            "m.ply:17: the file ends before face 1 of 2 (it is truncated)");
  EXPECT_EQ(PlyError(head + "0 0 0 0 0 1\n"),
            "m.ply:13: the file ends before vertex 1 of 4 (it is truncated)");
  EXPECT_EQ(PlyError(head + v + f + "\n3 0 1 2\n"), "m.ply:20: data after the last element");
  EXPECT_EQ(PlyError(head + v + f + "\n \n"), "(no error)");  // trailing blank lines
}

TEST(Ply, RefusesMalformedBinaryNamingTheElement) {
  const std::string good = BinaryPyramid(false);
  // The last face is 1 + 1 + 3·4 + 2 = 16 bytes.
  EXPECT_EQ(PlyError(good.substr(0, good.size() - 1)),
            "m.ply: face 4: the file ends inside it (it is truncated)");
  EXPECT_EQ(PlyError(good.substr(0, good.size() - 16)),
            "m.ply: the file ends before face 4 of 5 (it is truncated)");
  EXPECT_EQ(PlyError(good.substr(0, good.find("end_header\n") + 11)),
            "m.ply: the file ends before vertex 0 of 5 (it is truncated)");
  EXPECT_EQ(PlyError(good + "\n"),
            "m.ply: 1 byte after the last element (the header's counts do not match the data)");
  std::vector<PyramidFace> faces = kPyramidFaces;
  faces[1].indices[2] = 99;
  EXPECT_EQ(PlyError(BinaryPyramid(true, faces)),
            "m.ply: face 1: vertex index 99 out of range (the file has 5 vertices)");
  faces = kPyramidFaces;
  faces[3].indices = {2, 3};
  EXPECT_EQ(PlyError(BinaryPyramid(false, faces)),
            "m.ply: face 3: 2 vertices (a face needs at least 3)");
  faces[3].indices = {2, 3, 2};
  EXPECT_EQ(PlyError(BinaryPyramid(false, faces)), "m.ply: face 3: vertex 2 is named twice");
  // A NaN for vertex 2's x (the double after its y and red).
  std::string nan = good;
  const std::size_t vertex2 =
      good.find("end_header\n") + 11 + (4 + 1 + 8 + 4 + 1 + 8 + 12) + (4 + 1 + 8 + 4 + 1 + 12);
  std::string bits;
  PackDouble(&bits, std::nan(""), false);
  nan.replace(vertex2 + 5, 8, bits);
  EXPECT_EQ(PlyError(nan), "m.ply: vertex 2: x is not finite");
}

TEST(Ply, RefusesVerticesWhoseNormalCannotBeEstimated) {
  const std::string head =
      "format ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  EXPECT_EQ(PlyError("ply\n" + head + "0 0 0\n1 0 0\n0 1 0\n5 5 5\n3 0 1 2\n"),
            "m.ply:13: vertex 3 is in no face, so its normal cannot be estimated");
  std::string binary = "ply\nformat binary_big_endian 1.0\n" + head.substr(head.find('\n') + 1);
  for (const float c : {0.F, 0.F, 0.F, 1.F, 0.F, 0.F, 2.F, 0.F, 0.F, 0.F, 1.F, 0.F}) {
    PackFloat(&binary, c, true);
  }
  Pack(&binary, 3, 1, true);
  for (const int i : {0, 1, 2}) Pack(&binary, i, 4, true);
  EXPECT_EQ(PlyError(binary),
            "m.ply: vertex 0: the cross products of its faces sum to zero (no area, or they "
            "cancel), so its normal cannot be estimated");
}

// ---- Files and the examples ------------------------------------------------

TEST(MeshFile, ChoosesTheFormatBySuffixAndNamesTheFile) {
  EXPECT_EQ(ErrorOf([] { ReadMeshFile("mesh.stl"); }),
            "mesh.stl: unknown mesh format (expected a .obj or .ply file)");
  EXPECT_EQ(ErrorOf([] { ReadMeshFile("/nonexistent/m.OBJ"); }),
            "/nonexistent/m.OBJ: cannot open: No such file or directory");
  EXPECT_EQ(ErrorOf([] { ReadMeshFile(FDSURF_EXAMPLES_DIR "/teapot.bpt"); }),
            FDSURF_EXAMPLES_DIR "/teapot.bpt: unknown mesh format (expected a .obj or .ply file)");
}

// Every undirected edge in exactly two triangles, once each way: closed and
// consistently oriented. (The reader does not check this; the examples must
// be right.)
bool ClosedAndOriented(const TriangleMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    if (count != 1) return false;
    const auto back = directed.find({edge.second, edge.first});
    if (back == directed.end() || back->second != 1) return false;
  }
  return true;
}

// Each triangle's cross product points away from the origin.
bool WoundOutward(const TriangleMesh& mesh) {
  for (const auto& t : mesh.triangles) {
    const Point3& a = mesh.vertices[t[0]];
    const Point3 n = Cross(Sub(mesh.vertices[t[1]], a), Sub(mesh.vertices[t[2]], a));
    if (Dot(n, a) <= 0) return false;
  }
  return true;
}

TEST(MeshFile, ReadsTheOctahedron) {
  const TriangleMesh mesh = ReadMeshFile(FDSURF_EXAMPLES_DIR "/octahedron.obj");
  EXPECT_EQ(mesh.vertices,
            (std::vector<Point3>{
                {50, 0, 0}, {-50, 0, 0}, {0, 50, 0}, {0, -50, 0}, {0, 0, 50}, {0, 0, -50}}));
  EXPECT_EQ(
      mesh.normals,
      (std::vector<Point3>{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}));
  EXPECT_EQ(mesh.triangles.size(), 8u);
  EXPECT_TRUE(ClosedAndOriented(mesh));
  EXPECT_TRUE(WoundOutward(mesh));
  EXPECT_TRUE(mesh.notes.empty());
}

TEST(MeshFile, ReadsTheSubdividedIcosahedron) {
  const TriangleMesh mesh = ReadMeshFile(FDSURF_EXAMPLES_DIR "/sphere-icosa.obj");
  EXPECT_EQ(mesh.vertices.size(), 42u);
  EXPECT_EQ(mesh.triangles.size(), 80u);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    EXPECT_NEAR(Norm(mesh.vertices[i]), 50, 1e-12) << "vertex " << i;
    ExpectNear(mesh.normals[i], Scale(mesh.vertices[i], 1.0 / 50), 1e-15,
               "normal " + std::to_string(i));
  }
  EXPECT_TRUE(ClosedAndOriented(mesh));
  EXPECT_TRUE(WoundOutward(mesh));
  EXPECT_TRUE(mesh.notes.empty());
}

TEST(MeshFile, ReadsTheTerrain) {
  const TriangleMesh mesh = ReadMeshFile(FDSURF_EXAMPLES_DIR "/terrain.ply");
  ASSERT_EQ(mesh.vertices.size(), 25u);
  EXPECT_EQ(mesh.triangles.size(), 32u);
  // The grid point (i, j) is vertex 5j + i at (20i, 20j).
  for (int j = 0; j < 5; ++j) {
    for (int i = 0; i < 5; ++i) {
      const double x = 20.0 * i;
      const double y = 20.0 * j;
      const Point3& p = mesh.vertices[5 * j + i];
      EXPECT_EQ(p[0], x);
      EXPECT_EQ(p[1], y);
      EXPECT_NEAR(p[2], 6 * std::sin(x / 25) * std::cos(y / 30), 1e-15);
      const Point3 n = {-6.0 / 25 * std::cos(x / 25) * std::cos(y / 30),
                        6.0 / 30 * std::sin(x / 25) * std::sin(y / 30), 1};
      ExpectNear(mesh.normals[5 * j + i], Scale(n, 1 / Norm(n)), 1e-15,
                 "normal " + std::to_string(5 * j + i));
    }
  }
  for (const auto& t : mesh.triangles) {
    const Point3& a = mesh.vertices[t[0]];
    EXPECT_GT(Cross(Sub(mesh.vertices[t[1]], a), Sub(mesh.vertices[t[2]], a))[2], 0);
  }
  EXPECT_TRUE(mesh.notes.empty());
}

TEST(MeshFile, ReadsTheApple) {
  // examples/apple.ply from Debian's octave-matgeom: ASCII with float32,
  // uint8 and int32, no normals.
  const std::string path = FDSURF_EXAMPLES_DIR "/apple.ply";
  const TriangleMesh mesh = ReadMeshFile(path);
  EXPECT_EQ(mesh.vertices.size(), 867u);
  EXPECT_EQ(mesh.triangles.size(), 1704u);
  EXPECT_EQ(mesh.vertices[1], (Point3{0.0048, 0.0012, 0}));  // as written, not rounded to float
  EXPECT_TRUE(mesh.normals_estimated);
  EXPECT_EQ(mesh.notes,
            (std::vector<std::string>{path + ": no vertex normals; estimated (area-weighted)"}));
  for (const Point3& n : mesh.normals) EXPECT_NEAR(Norm(n), 1, 1e-15);
}

}  // namespace
}  // namespace fdsurf::host
