// SPDX-License-Identifier: MIT
#include "fdsurf/host/mesh_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string_view>

#include "fdsurf/host/vec3.h"

namespace fdsurf::host {
namespace {

// ---- Shared ---------------------------------------------------------------

// A sum of unit vectors (or of cross products) shorter than this fraction of
// the sum of their lengths has cancelled to rounding: it has no direction.
constexpr double kCancelled = 1e-12;

using Words = std::vector<std::string_view>;

Words SplitWords(std::string_view text) {
  Words words;
  std::size_t pos = 0;
  while (true) {
    pos = text.find_first_not_of(" \t\v\f\r", pos);
    if (pos == std::string_view::npos) break;
    std::size_t end = text.find_first_of(" \t\v\f\r", pos);
    if (end == std::string_view::npos) end = text.size();
    words.push_back(text.substr(pos, end - pos));
    pos = end;
  }
  return words;
}

std::string Quoted(std::string_view what, std::string_view word) {
  return std::string(what) + " '" + std::string(word) + "'";
}

// Parses a whole word as a double; the problem as a phrase ("x '1x' is not a
// number"), or empty. std::from_chars takes no leading '+', which files write.
std::string ParseDouble(std::string_view word, std::string_view what, double* value) {
  std::string_view digits = word;
  if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-' && digits[1] != '+') {
    digits.remove_prefix(1);
  }
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), *value);
  if (ec == std::errc::result_out_of_range) return Quoted(what, word) + " is out of range";
  if (ec != std::errc() || end != digits.data() + digits.size()) {
    return Quoted(what, word) + " is not a number";
  }
  if (!std::isfinite(*value)) return Quoted(what, word) + " is not finite";
  return "";
}

// Parses a whole word as an integer (optional '-'); false if it is not one.
bool ParseInteger(std::string_view word, long long* value) {
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), *value);
  return ec == std::errc() && end == word.data() + word.size();
}

std::string Count(std::size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// The unit vector along (x, y, z), or false for the zero vector. Scaling by
// the largest component first keeps tiny or huge components from
// underflowing or overflowing the sum of squares.
bool Normalise(Point3 v, Point3* unit) {
  const double m = std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])});
  if (m == 0) return false;
  v = Scale(v, 1 / m);
  *unit = Scale(v, 1 / Norm(v));
  return true;
}

// Where a message about vertex i points: "f.obj:5: vertex 3", "f.ply: vertex 2".
using VertexPlace = std::function<std::string(std::size_t)>;

// Fans a polygon of validated 0-based corners into triangles (c0, ci, ci+1):
// right for convex polygons. Returns the repeated vertex, or -1.
int AddPolygon(const std::vector<int>& corners, std::vector<std::array<int, 3>>* triangles) {
  std::vector<int> sorted = corners;
  std::sort(sorted.begin(), sorted.end());
  const auto twice = std::adjacent_find(sorted.begin(), sorted.end());
  if (twice != sorted.end()) return *twice;
  for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
    triangles->push_back({corners[0], corners[i], corners[i + 1]});
  }
  return -1;
}

// Area-weighted normals for the vertices with needed[i]: the sum of the
// cross products (b - a) x (c - a) of the triangles around each (twice their
// areas along their normals, so the winding orients it), normalised.
void EstimateNormals(const std::vector<Point3>& vertices,
                     const std::vector<std::array<int, 3>>& triangles,
                     const std::vector<char>& needed, const VertexPlace& place,
                     std::vector<Point3>* normals) {
  std::vector<Point3> sum(vertices.size(), Point3{0, 0, 0});
  std::vector<double> lengths(vertices.size(), 0.0);
  std::vector<char> in_face(vertices.size(), 0);
  for (const auto& t : triangles) {
    const Point3& a = vertices[t[0]];
    const Point3 n = Cross(Sub(vertices[t[1]], a), Sub(vertices[t[2]], a));
    for (const int k : t) {
      sum[k] = Add(sum[k], n);
      lengths[k] += Norm(n);
      in_face[k] = 1;
    }
  }
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (needed[i] == 0) continue;
    if (in_face[i] == 0) {
      throw InputError(place(i) + " is in no face, so its normal cannot be estimated");
    }
    if (!(Norm(sum[i]) > kCancelled * lengths[i]) || !Normalise(sum[i], &(*normals)[i])) {
      throw InputError(place(i) +
                       ": the cross products of its faces sum to zero (no area, or they cancel), "
                       "so its normal cannot be estimated");
    }
  }
}

std::string EstimatedNote(const std::string& name) {
  return name + ": no vertex normals; estimated (area-weighted)";
}

std::string FannedNote(const std::string& name, std::size_t fanned) {
  return name + ": " + Count(fanned, "polygon", "polygons") +
         " with more than 3 vertices fanned into triangles (right for convex polygons)";
}

// ---- OBJ ------------------------------------------------------------------

// A statement: one line, or several joined by trailing backslashes, without
// its comment; `number` is the line on which it starts.
struct ObjLine {
  int number = 0;
  std::string text;
};

std::vector<ObjLine> SplitObjLines(const std::string& text) {
  std::vector<ObjLine> lines;
  ObjLine pending;
  bool continuing = false;
  int number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    std::string_view line(text.data() + pos, eol - pos);
    pos = eol + 1;
    ++number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (!continuing) pending = ObjLine{number, ""};
    continuing = !line.empty() && line.back() == '\\';
    if (continuing) line.remove_suffix(1);
    pending.text.append(line);
    if (continuing) {
      pending.text.push_back(' ');
    } else {
      lines.push_back(pending);
    }
  }
  if (continuing) lines.push_back(pending);  // a backslash on the last line
  for (ObjLine& line : lines) line.text.erase(std::min(line.text.find('#'), line.text.size()));
  return lines;
}

// What an OBJ statement does here.
enum class ObjKind {
  kVertex,
  kNormal,
  kTexture,
  kFace,
  kSkipped,
  kNotSurface,
  kFreeForm,
  kUnknown
};

ObjKind KindOf(std::string_view keyword) {
  static constexpr std::string_view kSkipped[] = {
      "vp",  "o",     "g",        "s",        "mg",    "usemtl", "mtllib",     "maplib",   "usemap",
      "lod", "bevel", "c_interp", "d_interp", "ctech", "stech",  "shadow_obj", "trace_obj"};
  static constexpr std::string_view kFreeForm[] = {
      "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm", "trim", "hole",
      "scrv",   "sp",  "end",  "con",  "bsp",  "bzp",   "cdc",  "cdp",  "res"};
  if (keyword == "v") return ObjKind::kVertex;
  if (keyword == "vn") return ObjKind::kNormal;
  if (keyword == "vt") return ObjKind::kTexture;
  if (keyword == "f") return ObjKind::kFace;
  if (keyword == "p" || keyword == "l") return ObjKind::kNotSurface;
  if (std::find(std::begin(kSkipped), std::end(kSkipped), keyword) != std::end(kSkipped)) {
    return ObjKind::kSkipped;
  }
  if (std::find(std::begin(kFreeForm), std::end(kFreeForm), keyword) != std::end(kFreeForm)) {
    return ObjKind::kFreeForm;
  }
  return ObjKind::kUnknown;
}

// How many of each indexed statement the whole file has: a positive index
// may name a vertex defined further down.
struct ObjTotals {
  std::size_t vertices = 0;
  std::size_t textures = 0;
  std::size_t normals = 0;
};

class ObjReader {
 public:
  ObjReader(std::string name, const ObjTotals& totals)
      : name_(std::move(name)), totals_(totals), corner_normals_(totals.vertices) {}

  void Statement(const ObjLine& line);
  TriangleMesh Finish();

 private:
  FDSURF_NODISCARD InputError Error(const std::string& what) const {
    return InputError(name_ + ":" + std::to_string(line_) + ": " + what);
  }

  void Vertex(const Words& words);
  void Normal(const Words& words);
  void Face(const Words& words);
  int Index(std::string_view word, std::string_view part, const char* kind, const char* kinds,
            std::size_t so_far, std::size_t total) const;
  std::size_t AssignNormal(std::size_t vertex, Point3* normal) const;

  std::string name_;
  ObjTotals totals_;
  int line_ = 0;
  std::vector<Point3> vertices_;
  std::vector<int> vertex_lines_;
  std::vector<Point3> normals_;  // unit
  std::size_t textures_ = 0;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<std::vector<int>> corner_normals_;  // the vn each vertex's corners name
  std::size_t fanned_ = 0;
  std::size_t not_surface_ = 0;
  std::size_t unknown_ = 0;
  std::string first_unknown_;
  int first_unknown_line_ = 0;
};

void ObjReader::Statement(const ObjLine& line) {
  const Words words = SplitWords(line.text);
  if (words.empty()) return;
  line_ = line.number;
  switch (KindOf(words[0])) {
    case ObjKind::kVertex:
      Vertex(words);
      break;
    case ObjKind::kNormal:
      Normal(words);
      break;
    case ObjKind::kTexture:
      ++textures_;  // counted for the indices that name it; its values are not needed
      break;
    case ObjKind::kFace:
      Face(words);
      break;
    case ObjKind::kSkipped:
      break;
    case ObjKind::kNotSurface:
      ++not_surface_;
      break;
    case ObjKind::kFreeForm:
      throw Error(Quoted("free-form geometry", words[0]) +
                  " is not supported: only polygonal faces (f) are read");
    case ObjKind::kUnknown:
      if (unknown_++ == 0) {
        first_unknown_ = std::string(words[0]);
        first_unknown_line_ = line_;
      }
      break;
  }
}

void ObjReader::Vertex(const Words& words) {
  // x y z, x y z w (w weighs rational free-form geometry: no meaning for a
  // polygon's corner) or x y z r g b (the vertex-colour extension).
  const std::size_t n = words.size() - 1;
  if (n > 3 && n != 4 && n != 6) {
    throw Error("v: " + std::to_string(n) + " numbers (expected x y z, x y z w or x y z r g b)");
  }
  static const char* const kNames[2][6] = {{"x", "y", "z", "w", "", ""},
                                           {"x", "y", "z", "r", "g", "b"}};
  Point3 p{};
  for (std::size_t k = 0; k < n; ++k) {
    double value = 0;
    const std::string problem = ParseDouble(words[k + 1], kNames[n == 6 ? 1 : 0][k], &value);
    if (!problem.empty()) throw Error("v: " + problem);
    if (k < 3) p[k] = value;
  }
  if (n < 3) throw Error(std::string("v: missing ") + kNames[0][n]);
  vertices_.push_back(p);
  vertex_lines_.push_back(line_);
}

void ObjReader::Normal(const Words& words) {
  const std::size_t n = words.size() - 1;
  if (n > 3) throw Error("vn: " + std::to_string(n) + " numbers (expected i j k)");
  static const char* const kNames[3] = {"i", "j", "k"};
  Point3 v{};
  for (std::size_t k = 0; k < n; ++k) {
    const std::string problem = ParseDouble(words[k + 1], kNames[k], &v[k]);
    if (!problem.empty()) throw Error("vn: " + problem);
  }
  if (n < 3) throw Error(std::string("vn: missing ") + kNames[n]);
  Point3 unit{};
  if (!Normalise(v, &unit)) throw Error("vn: zero-length normal");
  normals_.push_back(unit);
}

// One index of a corner `word`, 0-based: positive ones count from 1 over the
// whole file, negative ones back from the latest statement of that kind.
int ObjReader::Index(std::string_view word, std::string_view part, const char* kind,
                     const char* kinds, std::size_t so_far, std::size_t total) const {
  long long index = 0;
  if (part.empty() || !ParseInteger(part, &index)) {
    throw Error("f: " + Quoted("corner", word) +
                " is not a vertex reference (v, v/vt, v//vn or v/vt/vn)");
  }
  const std::string head = "f: '" + std::string(word) + "': " + kind + " index ";
  if (index == 0) {
    throw Error(head + "0 (indices start at 1, or count back from -1 for the latest)");
  }
  if (index > 0 && static_cast<unsigned long long>(index) <= total) {
    return static_cast<int>(index - 1);
  }
  if (index < 0 && index >= -static_cast<long long>(so_far)) {
    return static_cast<int>(static_cast<long long>(so_far) + index);
  }
  const std::string range = index > 0 ? "the file has " + Count(total, kind, kinds)
                                      : Count(so_far, kind, kinds) + " before this line";
  throw Error(head + std::string(part) + " out of range (" + range + ")");
}

void ObjReader::Face(const Words& words) {
  if (words.size() < 4) {
    throw Error("f needs at least 3 vertices, found " + std::to_string(words.size() - 1));
  }
  std::vector<int> corners;
  std::vector<int> normals;
  for (std::size_t k = 1; k < words.size(); ++k) {
    const std::string_view word = words[k];
    const std::size_t slash1 = word.find('/');
    const std::size_t slash2 =
        slash1 == std::string_view::npos ? slash1 : word.find('/', slash1 + 1);
    const bool too_many =
        slash2 != std::string_view::npos && word.find('/', slash2 + 1) != std::string_view::npos;
    if (too_many) {
      throw Error("f: " + Quoted("corner", word) +
                  " is not a vertex reference (v, v/vt, v//vn or v/vt/vn)");
    }
    corners.push_back(Index(word, word.substr(0, slash1), "vertex", "vertices", vertices_.size(),
                            totals_.vertices));
    int normal = -1;
    if (slash1 != std::string_view::npos) {
      const std::string_view vt = word.substr(slash1 + 1, slash2 - slash1 - 1);
      // v/vt needs vt; v//vn may leave it out.
      if (!vt.empty() || slash2 == std::string_view::npos) {
        Index(word, vt, "texture coordinate", "texture coordinates", textures_, totals_.textures);
      }
    }
    if (slash2 != std::string_view::npos) {
      normal = Index(word, word.substr(slash2 + 1), "normal", "normals", normals_.size(),
                     totals_.normals);
    }
    normals.push_back(normal);
  }
  const int twice = AddPolygon(corners, &triangles_);
  if (twice >= 0) throw Error("f: vertex " + std::to_string(twice + 1) + " is named twice");
  if (corners.size() > 3) ++fanned_;
  for (std::size_t k = 0; k < corners.size(); ++k) {
    if (normals[k] >= 0) corner_normals_[corners[k]].push_back(normals[k]);
  }
}

// The normal the corners of `vertex` give it: the vn they name, or the
// normalised mean of the distinct ones. Returns how many distinct ones they
// name (0: none, the normal is to be estimated).
std::size_t ObjReader::AssignNormal(std::size_t vertex, Point3* normal) const {
  std::vector<Point3> distinct;
  for (const int n : corner_normals_[vertex]) {
    if (std::find(distinct.begin(), distinct.end(), normals_[n]) == distinct.end()) {
      distinct.push_back(normals_[n]);
    }
  }
  if (distinct.empty()) return 0;
  Point3 sum{0, 0, 0};
  for (const Point3& n : distinct) sum = Add(sum, n);
  if (!(Norm(sum) > kCancelled * static_cast<double>(distinct.size())) || !Normalise(sum, normal)) {
    throw InputError(name_ + ":" + std::to_string(vertex_lines_[vertex]) + ": vertex " +
                     std::to_string(vertex + 1) +
                     ": its corners name normals that cancel (their mean is zero)");
  }
  return distinct.size();
}

TriangleMesh ObjReader::Finish() {
  if (triangles_.empty()) throw InputError(name_ + ": no faces (f) in the file");
  TriangleMesh mesh;
  mesh.vertices = vertices_;
  mesh.triangles = triangles_;
  mesh.normals.assign(vertices_.size(), Point3{0, 0, 0});
  std::vector<char> needed(vertices_.size(), 0);
  std::size_t missing = 0;
  std::size_t averaged = 0;
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    const std::size_t distinct = AssignNormal(i, &mesh.normals[i]);
    if (distinct == 0) {
      needed[i] = 1;
      ++missing;
    } else if (distinct > 1) {
      ++averaged;
    }
  }
  EstimateNormals(
      mesh.vertices, mesh.triangles, needed,
      [this](std::size_t i) {
        return name_ + ":" + std::to_string(vertex_lines_[i]) + ": vertex " + std::to_string(i + 1);
      },
      &mesh.normals);
  mesh.normals_estimated = missing == vertices_.size();
  if (mesh.normals_estimated) {
    mesh.notes.push_back(EstimatedNote(name_));
  } else if (missing > 0) {
    mesh.notes.push_back(name_ + ": " + std::to_string(missing) + " of " +
                         Count(vertices_.size(), "vertex", "vertices") +
                         " have no normal (their faces name none); estimated (area-weighted)");
  }
  if (averaged > 0) {
    mesh.notes.push_back(name_ + ": " + Count(averaged, "vertex has", "vertices have") +
                         " corners naming different normals; each takes their normalised mean");
  }
  if (fanned_ > 0) mesh.notes.push_back(FannedNote(name_, fanned_));
  if (not_surface_ > 0) {
    mesh.notes.push_back(
        name_ + ": " + Count(not_surface_, "point or line statement", "point and line statements") +
        " (p, l) skipped: they are not surfaces");
  }
  if (unknown_ > 0) {
    mesh.notes.push_back(name_ + ": " + Count(unknown_, "unknown statement", "unknown statements") +
                         " skipped (the first, '" + first_unknown_ + "', on line " +
                         std::to_string(first_unknown_line_) + ")");
  }
  return mesh;
}

// ---- PLY ------------------------------------------------------------------

enum class PlyType : std::uint8_t {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kFloat,
  kDouble
};

struct PlyTypeInfo {
  PlyType type;
  std::string_view name;
  std::string_view alias;
  std::size_t size;
  bool integer;
  long long min;
  long long max;
};

constexpr PlyTypeInfo kPlyTypes[] = {
    {PlyType::kInt8, "char", "int8", 1, true, -128, 127},
    {PlyType::kUint8, "uchar", "uint8", 1, true, 0, 255},
    {PlyType::kInt16, "short", "int16", 2, true, -32768, 32767},
    {PlyType::kUint16, "ushort", "uint16", 2, true, 0, 65535},
    {PlyType::kInt32, "int", "int32", 4, true, -2147483648LL, 2147483647LL},
    {PlyType::kUint32, "uint", "uint32", 4, true, 0, 4294967295LL},
    {PlyType::kFloat, "float", "float32", 4, false, 0, 0},
    {PlyType::kDouble, "double", "float64", 8, false, 0, 0},
};

const PlyTypeInfo& Info(PlyType type) { return kPlyTypes[static_cast<int>(type)]; }

struct PlyProperty {
  std::string name;
  int line = 0;
  bool list = false;
  PlyType count_type = PlyType::kUint8;
  PlyType type = PlyType::kFloat;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  int line = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyFormat : std::uint8_t { kNone, kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyHeader {
  PlyFormat format = PlyFormat::kNone;
  std::vector<PlyElement> elements;
  std::size_t body = 0;  // offset of the first byte after end_header's line
  int end_header_line = 0;
};

// Reads the header's lines (LF or CRLF) up to end_header.
class PlyHeaderReader {
 public:
  PlyHeaderReader(const std::string& bytes, const std::string& name) : bytes_(bytes), name_(name) {}

  PlyHeader Read();

 private:
  FDSURF_NODISCARD InputError Error(const std::string& what) const {
    return InputError(name_ + ":" + std::to_string(line_) + ": " + what);
  }
  // The next line, or false at the end of the bytes.
  bool NextLine(std::string_view* line);
  void Format(const Words& words);
  void Element(const Words& words);
  void Property(const Words& words);
  FDSURF_NODISCARD PlyType Type(std::string_view word) const;

  const std::string& bytes_;
  const std::string& name_;
  std::size_t pos_ = 0;
  int line_ = 0;
  PlyHeader header_;
};

bool PlyHeaderReader::NextLine(std::string_view* line) {
  if (pos_ >= bytes_.size()) return false;
  std::size_t eol = bytes_.find('\n', pos_);
  if (eol == std::string::npos) eol = bytes_.size();
  *line = std::string_view(bytes_).substr(pos_, eol - pos_);
  if (!line->empty() && line->back() == '\r') line->remove_suffix(1);
  pos_ = eol + 1;
  ++line_;
  return true;
}

PlyHeader PlyHeaderReader::Read() {
  std::string_view line;
  if (!NextLine(&line) || line != "ply") {
    line_ = 1;
    throw Error("not a PLY file (the first line is not 'ply')");
  }
  while (true) {
    if (!NextLine(&line)) throw Error("the header has no end_header");
    const Words words = SplitWords(line);
    if (words.empty()) continue;
    const std::string_view keyword = words[0];
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      Format(words);
    } else if (keyword == "element") {
      Element(words);
    } else if (keyword == "property") {
      Property(words);
    } else if (keyword == "end_header" && words.size() == 1) {
      break;
    } else {
      throw Error("unknown header line " + Quoted("starting", keyword));
    }
  }
  if (header_.format == PlyFormat::kNone) throw Error("no format line before end_header");
  header_.body = std::min(pos_, bytes_.size());
  header_.end_header_line = line_;
  return header_;
}

void PlyHeaderReader::Format(const Words& words) {
  if (header_.format != PlyFormat::kNone) throw Error("a second format line");
  if (words.size() != 3) throw Error("format takes a format and a version: 'format ascii 1.0'");
  if (words[1] == "ascii") {
    header_.format = PlyFormat::kAscii;
  } else if (words[1] == "binary_little_endian") {
    header_.format = PlyFormat::kBinaryLittleEndian;
  } else if (words[1] == "binary_big_endian") {
    header_.format = PlyFormat::kBinaryBigEndian;
  } else {
    throw Error("unknown " + Quoted("format", words[1]) +
                " (expected ascii, binary_little_endian or binary_big_endian)");
  }
  if (words[2] != "1.0")
    throw Error("unsupported " + Quoted("version", words[2]) + " (expected 1.0)");
}

void PlyHeaderReader::Element(const Words& words) {
  if (words.size() != 3) throw Error("element takes a name and a count: 'element vertex 8'");
  PlyElement element;
  element.name = std::string(words[1]);
  element.line = line_;
  const auto [end, ec] =
      std::from_chars(words[2].data(), words[2].data() + words[2].size(), element.count);
  if (ec != std::errc() || end != words[2].data() + words[2].size()) {
    throw Error("element " + element.name + ": " + Quoted("count", words[2]) +
                " is not a whole number");
  }
  for (const PlyElement& e : header_.elements) {
    if (e.name == element.name) throw Error("a second element " + element.name);
  }
  header_.elements.push_back(element);
}

PlyType PlyHeaderReader::Type(std::string_view word) const {
  for (const PlyTypeInfo& info : kPlyTypes) {
    if (word == info.name || word == info.alias) return info.type;
  }
  throw Error("unknown " + Quoted("type", word) +
              " (expected char, uchar, short, ushort, int, uint, float, double or their "
              "int8 ... float64 names)");
}

void PlyHeaderReader::Property(const Words& words) {
  if (header_.elements.empty()) throw Error("property before any element");
  PlyElement& element = header_.elements.back();
  PlyProperty property;
  property.line = line_;
  if (words.size() == 5 && words[1] == "list") {
    property.list = true;
    property.count_type = Type(words[2]);
    property.type = Type(words[3]);
    if (!Info(property.count_type).integer) {
      throw Error("the count type of a list must be an integer type, not " + std::string(words[2]));
    }
  } else if (words.size() == 3 && words[1] != "list") {
    property.type = Type(words[1]);
  } else {
    throw Error(
        "property takes a type and a name ('property float x') or 'list', two types and "
        "a name ('property list uchar int vertex_indices')");
  }
  property.name = std::string(words.back());
  for (const PlyProperty& p : element.properties) {
    if (p.name == property.name) {
      throw Error("a second property " + property.name + " in element " + element.name);
    }
  }
  element.properties.push_back(property);
}

// Which elements and properties hold the mesh.
struct PlyLayout {
  std::size_t vertex = 0;  // element indices
  std::size_t face = 0;
  int xyz[3] = {-1, -1, -1};  // property indices in the vertex element
  int normal[3] = {-1, -1, -1};
  int indices = -1;  // the list property in the face element
};

int FindProperty(const PlyElement& element, std::string_view name) {
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    if (element.properties[p].name == name) return static_cast<int>(p);
  }
  return -1;
}

std::size_t FindElement(const PlyHeader& header, const std::string& element,
                        const std::string& name) {
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    if (header.elements[e].name == element) return e;
  }
  throw InputError(name + ":" + std::to_string(header.end_header_line) +
                   ": the header has no element " + element);
}

void FindVertexProperties(const PlyElement& vertex, const std::string& name, PlyLayout* layout) {
  const auto error = [&](int line, const std::string& what) {
    return InputError(name + ":" + std::to_string(line) + ": " + what);
  };
  static const char* const kXyz[3] = {"x", "y", "z"};
  static const char* const kNormal[3] = {"nx", "ny", "nz"};
  int normals = 0;
  for (int k = 0; k < 3; ++k) {
    layout->xyz[k] = FindProperty(vertex, kXyz[k]);
    if (layout->xyz[k] < 0) {
      throw error(vertex.line, std::string("element vertex has no property ") + kXyz[k]);
    }
    layout->normal[k] = FindProperty(vertex, kNormal[k]);
    normals += layout->normal[k] >= 0 ? 1 : 0;
    for (const int p : {layout->xyz[k], layout->normal[k]}) {
      if (p >= 0 && vertex.properties[p].list) {
        throw error(vertex.properties[p].line, "property " + vertex.properties[p].name +
                                                   " of element vertex must be a scalar");
      }
    }
  }
  if (normals != 0 && normals != 3) {
    throw error(vertex.line, "element vertex has only some of nx ny nz (give all three or none)");
  }
}

PlyLayout FindLayout(const PlyHeader& header, const std::string& name) {
  PlyLayout layout;
  layout.vertex = FindElement(header, "vertex", name);
  layout.face = FindElement(header, "face", name);
  const PlyElement& vertex = header.elements[layout.vertex];
  const PlyElement& face = header.elements[layout.face];
  const auto error = [&](int line, const std::string& what) {
    return InputError(name + ":" + std::to_string(line) + ": " + what);
  };
  FindVertexProperties(vertex, name, &layout);
  if (vertex.count > static_cast<std::uint64_t>(std::numeric_limits<int>::max())) {
    throw error(vertex.line, "element vertex: more vertices than this reader takes (" +
                                 std::to_string(std::numeric_limits<int>::max()) + ")");
  }
  const int indices = FindProperty(face, "vertex_indices");
  const int index = FindProperty(face, "vertex_index");
  if (indices >= 0 && index >= 0) {
    throw error(face.line, "element face has both vertex_indices and vertex_index");
  }
  layout.indices = std::max(indices, index);
  if (layout.indices < 0) {
    throw error(face.line, "element face has no list property vertex_indices (or vertex_index)");
  }
  const PlyProperty& list = face.properties[layout.indices];
  if (!list.list)
    throw error(list.line, "property " + list.name + " of element face must be a list");
  if (!Info(list.type).integer) {
    throw error(list.line, "the entries of " + list.name + " must be of an integer type, not " +
                               std::string(Info(list.type).name));
  }
  if (face.count == 0) throw error(face.line, "element face has no faces (count 0)");
  return layout;
}

// The body of an ASCII PLY: one element a line (blank lines skipped).
class PlyAsciiSource {
 public:
  PlyAsciiSource(const std::string& bytes, const PlyHeader& header, const std::string& name)
      : bytes_(bytes), name_(name), pos_(header.body), line_(header.end_header_line) {}

  void Begin(const PlyElement& element, std::uint64_t index) {
    element_ = &element;
    index_ = index;
    if (element.properties.empty()) {  // nothing to read, not even a line
      words_.clear();
      next_ = 0;
      return;
    }
    if (!NextNonBlank()) {
      throw InputError(name_ + ":" + std::to_string(line_) + ": the file ends before " +
                       element.name + " " + std::to_string(index) + " of " +
                       std::to_string(element.count) + " (it is truncated)");
    }
  }

  double Value(PlyType type, const std::string& what) {
    if (next_ >= words_.size()) throw Error("the line ends where " + what + " was expected");
    const std::string_view word = words_[next_++];
    const PlyTypeInfo& info = Info(type);
    if (!info.integer) {
      double value = 0;
      const std::string problem = ParseDouble(word, what, &value);
      if (!problem.empty()) throw Error(problem);
      return value;
    }
    long long value = 0;
    if (!ParseInteger(word, &value)) throw Error(Quoted(what, word) + " is not a whole number");
    if (value < info.min || value > info.max) {
      throw Error(Quoted(what, word) + " is out of range for " + std::string(info.name));
    }
    return static_cast<double>(value);
  }

  void End() {
    if (next_ < words_.size()) {
      throw Error(Quoted("unexpected value", words_[next_]) + " after the last property");
    }
  }

  void Finish() {
    if (NextNonBlank()) {
      throw InputError(name_ + ":" + std::to_string(line_) + ": data after the last element");
    }
  }

  FDSURF_NODISCARD int line() const { return line_; }

  FDSURF_NODISCARD InputError Error(const std::string& what) const {
    return InputError(name_ + ":" + std::to_string(line_) + ": " + element_->name + " " +
                      std::to_string(index_) + ": " + what);
  }

 private:
  bool NextNonBlank() {
    while (pos_ < bytes_.size()) {
      std::size_t eol = bytes_.find('\n', pos_);
      if (eol == std::string::npos) eol = bytes_.size();
      words_ = SplitWords(std::string_view(bytes_).substr(pos_, eol - pos_));
      next_ = 0;
      pos_ = eol + 1;
      ++line_;
      if (!words_.empty()) return true;
    }
    return false;
  }

  const std::string& bytes_;
  const std::string& name_;
  std::size_t pos_;
  int line_;
  Words words_;
  std::size_t next_ = 0;
  const PlyElement* element_ = nullptr;
  std::uint64_t index_ = 0;
};

// The body of a binary PLY, either byte order.
class PlyBinarySource {
 public:
  PlyBinarySource(const std::string& bytes, const PlyHeader& header, const std::string& name)
      : bytes_(bytes),
        name_(name),
        pos_(header.body),
        swap_((header.format == PlyFormat::kBinaryLittleEndian) !=
              (std::endian::native == std::endian::little)) {}

  void Begin(const PlyElement& element, std::uint64_t index) {
    element_ = &element;
    index_ = index;
    if (pos_ >= bytes_.size() && !element.properties.empty()) {
      throw InputError(name_ + ": the file ends before " + element.name + " " +
                       std::to_string(index) + " of " + std::to_string(element.count) +
                       " (it is truncated)");
    }
  }

  double Value(PlyType type, const std::string& /*what*/) {
    if (bytes_.size() - pos_ < Info(type).size) {
      throw Error("the file ends inside it (it is truncated)");
    }
    const char* p = bytes_.data() + pos_;
    pos_ += Info(type).size;
    switch (type) {
      case PlyType::kInt8:
        return Load<std::int8_t>(p);
      case PlyType::kUint8:
        return Load<std::uint8_t>(p);
      case PlyType::kInt16:
        return Load<std::int16_t>(p);
      case PlyType::kUint16:
        return Load<std::uint16_t>(p);
      case PlyType::kInt32:
        return Load<std::int32_t>(p);
      case PlyType::kUint32:
        return Load<std::uint32_t>(p);
      case PlyType::kFloat:
        return Load<float>(p);
      case PlyType::kDouble:
        return Load<double>(p);
    }
    return 0;
  }

  void End() {}

  void Finish() {
    if (pos_ < bytes_.size()) {
      throw InputError(name_ + ": " + Count(bytes_.size() - pos_, "byte", "bytes") +
                       " after the last element (the header's counts do not match the data)");
    }
  }

  FDSURF_NODISCARD int line() const { return 0; }

  FDSURF_NODISCARD InputError Error(const std::string& what) const {
    return InputError(name_ + ": " + element_->name + " " + std::to_string(index_) + ": " + what);
  }

 private:
  template <class T>
  double Load(const char* p) const {
    std::array<char, sizeof(T)> raw{};
    std::memcpy(raw.data(), p, sizeof(T));
    if (swap_) std::reverse(raw.begin(), raw.end());
    return static_cast<double>(std::bit_cast<T>(raw));
  }

  const std::string& bytes_;
  const std::string& name_;
  std::size_t pos_;
  bool swap_;
  const PlyElement* element_ = nullptr;
  std::uint64_t index_ = 0;
};

// The mesh as the body gives it.
struct PlyData {
  std::vector<Point3> vertices;
  std::vector<Point3> normals;
  std::vector<int> vertex_lines;  // ASCII only
  std::vector<std::array<int, 3>> triangles;
  std::size_t fanned = 0;
};

template <class Source>
void AddPlyVertex(const std::vector<double>& values, const PlyLayout& layout,
                  const PlyElement& element, Source* source, PlyData* data) {
  Point3 p{};
  Point3 n{};
  for (int k = 0; k < 3; ++k) {
    for (const int prop : {layout.xyz[k], layout.normal[k]}) {
      if (prop >= 0 && !std::isfinite(values[prop])) {
        throw source->Error(element.properties[prop].name + " is not finite");
      }
    }
    p[k] = values[layout.xyz[k]];
    if (layout.normal[k] >= 0) n[k] = values[layout.normal[k]];
  }
  data->vertices.push_back(p);
  data->vertex_lines.push_back(source->line());
  if (layout.normal[0] < 0) return;
  Point3 unit{};
  if (!Normalise(n, &unit)) throw source->Error("zero-length normal (nx ny nz)");
  data->normals.push_back(unit);
}

template <class Source>
void AddPlyFace(const std::vector<double>& list, std::uint64_t vertex_count, Source* source,
                PlyData* data) {
  if (list.size() < 3) {
    throw source->Error(Count(list.size(), "vertex", "vertices") + " (a face needs at least 3)");
  }
  std::vector<int> corners;
  for (const double v : list) {
    if (v < 0 || v >= static_cast<double>(vertex_count)) {
      throw source->Error("vertex index " + std::to_string(static_cast<long long>(v)) +
                          " out of range (the file has " +
                          Count(vertex_count, "vertex", "vertices") + ")");
    }
    corners.push_back(static_cast<int>(v));
  }
  const int twice = AddPolygon(corners, &data->triangles);
  if (twice >= 0) throw source->Error("vertex " + std::to_string(twice) + " is named twice");
  if (corners.size() > 3) ++data->fanned;
}

// Reads every element in header order, keeping the vertices' scalars and the
// faces' index lists; other elements and properties are read and dropped.
template <class Source>
PlyData ReadPlyBody(const PlyHeader& header, const PlyLayout& layout, Source* source) {
  PlyData data;
  std::vector<double> list;
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    std::vector<double> values(element.properties.size(), 0.0);
    const int wanted = e == layout.face ? layout.indices : -1;
    for (std::uint64_t i = 0; i < element.count; ++i) {
      source->Begin(element, i);
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (!property.list) {
          values[p] = source->Value(property.type, property.name);
          continue;
        }
        const double count = source->Value(property.count_type, property.name + " count");
        if (count < 0) throw source->Error(property.name + " count is negative");
        const bool keep = static_cast<int>(p) == wanted;
        if (keep) list.clear();
        const auto entries = static_cast<std::uint64_t>(count);
        for (std::uint64_t k = 0; k < entries; ++k) {
          const double value = source->Value(property.type, property.name + " entry");
          if (keep) list.push_back(value);
        }
      }
      source->End();
      if (e == layout.vertex) AddPlyVertex(values, layout, element, source, &data);
      if (e == layout.face) AddPlyFace(list, header.elements[layout.vertex].count, source, &data);
    }
  }
  source->Finish();
  return data;
}

// ---- Files ----------------------------------------------------------------

bool EndsWithNoCase(const std::string& s, std::string_view suffix) {
  if (s.size() < suffix.size()) return false;
  for (std::size_t i = 0; i < suffix.size(); ++i) {
    const char c = s[s.size() - suffix.size() + i];
    if (std::tolower(static_cast<unsigned char>(c)) != suffix[i]) return false;
  }
  return true;
}

}  // namespace

TriangleMesh ParseObj(const std::string& text, const std::string& name) {
  const std::vector<ObjLine> lines = SplitObjLines(text);
  ObjTotals totals;
  for (const ObjLine& line : lines) {
    const Words words = SplitWords(line.text);
    if (words.empty()) continue;
    if (words[0] == "v") ++totals.vertices;
    if (words[0] == "vt") ++totals.textures;
    if (words[0] == "vn") ++totals.normals;
  }
  ObjReader reader(name, totals);
  for (const ObjLine& line : lines) reader.Statement(line);
  return reader.Finish();
}

TriangleMesh ParsePly(const std::string& bytes, const std::string& name) {
  const PlyHeader header = PlyHeaderReader(bytes, name).Read();
  const PlyLayout layout = FindLayout(header, name);
  PlyData data;
  if (header.format == PlyFormat::kAscii) {
    PlyAsciiSource source(bytes, header, name);
    data = ReadPlyBody(header, layout, &source);
  } else {
    PlyBinarySource source(bytes, header, name);
    data = ReadPlyBody(header, layout, &source);
  }
  TriangleMesh mesh;
  mesh.vertices = std::move(data.vertices);
  mesh.triangles = std::move(data.triangles);
  if (data.normals.empty()) {
    mesh.normals.assign(mesh.vertices.size(), Point3{0, 0, 0});
    const std::vector<char> needed(mesh.vertices.size(), 1);
    EstimateNormals(
        mesh.vertices, mesh.triangles, needed,
        [&](std::size_t i) {
          const int line = data.vertex_lines[i];
          return name + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": vertex " +
                 std::to_string(i);
        },
        &mesh.normals);
    mesh.normals_estimated = true;
    mesh.notes.push_back(EstimatedNote(name));
  } else {
    mesh.normals = std::move(data.normals);
  }
  if (data.fanned > 0) mesh.notes.push_back(FannedNote(name, data.fanned));
  return mesh;
}

TriangleMesh ReadMeshFile(const std::string& path) {
  const bool obj = EndsWithNoCase(path, ".obj");
  if (!obj && !EndsWithNoCase(path, ".ply")) {
    throw InputError(path + ": unknown mesh format (expected a .obj or .ply file)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path + ": read error");
  return obj ? ParseObj(buffer.str(), path) : ParsePly(buffer.str(), path);
}

}  // namespace fdsurf::host
