// SPDX-License-Identifier: MIT
#include "fdsurf/host/patch_io.h"

#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "construct_io.h"
#include "fdsurf/host/gcode_io.h"
#include "fdsurf/host/svg_io.h"

namespace fdsurf::host {
namespace {

// ---- BPT ------------------------------------------------------------------

// Splits BPT text into whitespace-separated tokens, remembering each line.
class BptTokens {
 public:
  BptTokens(const std::string& text, std::string name) : text_(text), name_(std::move(name)) {}

  // The next token, or an empty view at the end of the text.
  std::string_view Next() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    // At the end of the text, report the line of the last token: an editor
    // shows no line after a final newline.
    if (pos_ < text_.size()) token_line_ = line_;
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    return std::string_view(text_).substr(start, pos_ - start);
  }

  FDSURF_NODISCARD InputError Error(const std::string& what) const {
    return InputError(name_ + ":" + std::to_string(token_line_) + ": " + what);
  }

  FDSURF_NODISCARD int line() const { return token_line_; }
  FDSURF_NODISCARD const std::string& name() const { return name_; }

  double Number(const char* what) {
    const std::string_view token = Next();
    if (token.empty()) throw Error(std::string("file ends where ") + what + " was expected");
    double value = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec == std::errc::result_out_of_range) {
      throw Error(std::string(what) + " '" + std::string(token) + "' is out of range");
    }
    if (ec != std::errc() || end != token.data() + token.size()) {
      throw Error(std::string(what) + " '" + std::string(token) + "' is not a number");
    }
    if (!std::isfinite(value)) {
      throw Error(std::string(what) + " '" + std::string(token) + "' is not finite");
    }
    return value;
  }

  long Integer(const char* what) {
    const std::string_view token = Next();
    if (token.empty()) throw Error(std::string("file ends where ") + what + " was expected");
    long value = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || end != token.data() + token.size()) {
      throw Error(std::string(what) + " '" + std::string(token) + "' is not a whole number");
    }
    return value;
  }

 private:
  const std::string& text_;
  std::string name_;
  std::size_t pos_ = 0;
  int line_ = 1;
  int token_line_ = 1;
};

// ---- JSON -----------------------------------------------------------------

using Net = std::vector<std::vector<Point3>>;

Net ParseNet(const nlohmann::json& value, const JsonPlace& place) {
  if (!value.is_array() || value.empty()) throw place.Error("must be a non-empty array of rows");
  Net net;
  for (std::size_t r = 0; r < value.size(); ++r) {
    const JsonPlace row_place = place.Index(r);
    const nlohmann::json& row = value[r];
    if (!row.is_array() || row.empty())
      throw row_place.Error("must be a non-empty array of points");
    if (r > 0 && row.size() != net[0].size()) {
      throw row_place.Error("has " + std::to_string(row.size()) + " points but row 0 has " +
                            std::to_string(net[0].size()));
    }
    std::vector<Point3> points;
    for (std::size_t c = 0; c < row.size(); ++c) {
      const JsonPlace point_place = row_place.Index(c);
      const nlohmann::json& point = row[c];
      if (!point.is_array() || point.size() != 3) {
        throw point_place.Error("must be a point [x, y, z]");
      }
      Point3 p{};
      for (std::size_t k = 0; k < 3; ++k) {
        if (!point[k].is_number()) throw point_place.Index(k).Error("must be a number");
        p[k] = point[k].get<double>();
        if (!std::isfinite(p[k])) throw point_place.Index(k).Error("must be finite");
      }
      points.push_back(p);
    }
    net.push_back(std::move(points));
  }
  return net;
}

std::string NetShape(const Net& net) {
  return std::to_string(net.size()) + "x" + std::to_string(net[0].size());
}

// Cuts a net into 4×4 windows: `stride` 3 for Bézier (shared edges), 1 for the
// splines (overlapping windows).
void AddPatches(const Net& net, Basis basis, std::size_t stride, const JsonPlace& place,
                PatchSet* set) {
  const std::size_t rows = (net.size() - 4) / stride + 1;
  const std::size_t cols = (net[0].size() - 4) / stride + 1;
  for (std::size_t a = 0; a < rows; ++a) {
    for (std::size_t b = 0; b < cols; ++b) {
      Patch patch;
      patch.basis = basis;
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) patch.g[i][j] = net[a * stride + i][b * stride + j];
      }
      patch.origin = place.file + ": " + place.path + " patch (" + std::to_string(a) + "," +
                     std::to_string(b) + ")";
      set->patches.push_back(patch);
    }
  }
}

void AddSurface(const nlohmann::json& surface, const JsonPlace& place, PatchSet* set) {
  if (!surface.is_object()) throw place.Error(R"(must be an object with "basis" and "net")");
  for (const auto& [key, unused] : surface.items()) {
    if (key != "basis" && key != "net") {
      throw place.Error(R"(unknown field ")" + key + R"(" (expected "basis" and "net"))");
    }
  }
  if (!surface.contains("basis")) throw place.Error(R"(missing "basis")");
  if (!surface.contains("net")) throw place.Error(R"(missing "net")");
  const Basis basis = ParseBasis(surface["basis"], place.Child("basis"));
  const JsonPlace net_place = place.Child("net");
  const Net net = ParseNet(surface["net"], net_place);
  const std::size_t rows = net.size();
  const std::size_t cols = net[0].size();
  switch (basis) {
    case Basis::kBezier:
      if (rows < 4 || cols < 4 || (rows - 1) % 3 != 0 || (cols - 1) % 3 != 0) {
        throw net_place.Error("a bezier net must be (3m+1)x(3n+1) points, got " + NetShape(net));
      }
      AddPatches(net, basis, 3, place, set);
      break;
    case Basis::kBSpline:
    case Basis::kCatmullRom:
      if (rows < 4 || cols < 4) {
        throw net_place.Error(std::string("a ") + BasisName(basis) +
                              " net needs at least 4x4 points, got " + NetShape(net));
      }
      AddPatches(net, basis, 1, place, set);
      break;
    case Basis::kHermite:
    case Basis::kPower:
      if (rows != 4 || cols != 4) {
        throw net_place.Error(std::string("a ") + BasisName(basis) +
                              " net must be exactly 4x4, got " + NetShape(net));
      }
      AddPatches(net, basis, 1, place, set);
      break;
  }
}

// "line L, column C" of a byte offset, for parse errors.
std::string LineAndColumn(const std::string& text, std::size_t offset) {
  int line = 1;
  std::size_t line_start = 0;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  return std::to_string(line) + ":" + std::to_string(offset - line_start + 1);
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

PatchSet ParseBpt(const std::string& text, const std::string& name) {
  BptTokens tokens(text, name);
  const long count = tokens.Integer("the number of patches");
  if (count < 1 || count > 1000000) {
    throw tokens.Error("the number of patches must be between 1 and 1000000, got " +
                       std::to_string(count));
  }
  PatchSet set;
  set.patches.reserve(static_cast<std::size_t>(count));
  for (long p = 0; p < count; ++p) {
    const std::string_view first = tokens.Next();
    if (first.empty()) {
      throw tokens.Error("file ends after " + std::to_string(p) + " of " + std::to_string(count) +
                         " patches");
    }
    const int header_line = tokens.line();
    const std::string_view second = tokens.Next();
    if (first != "3" || second != "3") {
      throw InputError(name + ":" + std::to_string(header_line) + ": patch " + std::to_string(p) +
                       ": expected the degrees '3 3', found '" + std::string(first) + " " +
                       std::string(second) + "' (only bicubic patches are supported)");
    }
    Patch patch;
    patch.basis = Basis::kBezier;
    patch.origin = name + ":" + std::to_string(header_line) + " (patch " + std::to_string(p) + ")";
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        for (int c = 0; c < 3; ++c) {
          static const char* const kWhat[3] = {"x", "y", "z"};
          patch.g[i][j][c] = tokens.Number(kWhat[c]);
        }
      }
    }
    set.patches.push_back(patch);
  }
  if (!tokens.Next().empty()) {
    throw tokens.Error("unexpected data after the last of " + std::to_string(count) + " patches");
  }
  return set;
}

PatchSet ParseJson(const std::string& text, const std::string& name) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    std::string what = e.what();
    // nlohmann's message repeats its own position; keep the description only.
    const std::size_t colon = what.find(": ", what.find("parse error"));
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw InputError(name + ":" + LineAndColumn(text, e.byte > 0 ? e.byte - 1 : 0) +
                     ": invalid JSON: " + what);
  } catch (const nlohmann::json::exception& e) {
    // E.g. "number overflow parsing '1e400'": nlohmann gives no position.
    std::string what = e.what();
    const std::size_t bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    throw InputError(name + ": invalid JSON: " + what);
  }
  const JsonPlace root{name, ""};
  if (!doc.is_object()) throw root.Error("the top level must be an object");
  for (const auto& [key, unused] : doc.items()) {
    if (key != "units" && key != "surfaces" && key != "construct" && key != "curves") {
      throw root.Error(R"(unknown field ")" + key +
                       R"(" (expected "units", "surfaces", "construct" and "curves"))");
    }
  }
  PatchSet set;
  if (doc.contains("units")) {
    const nlohmann::json& units = doc["units"];
    if (!units.is_string() || (units != "mm" && units != "in")) {
      throw root.Child("units").Error(R"(must be "mm" or "in")");
    }
    set.units = units.get<std::string>();
  }
  const bool constructs = doc.contains("construct") || doc.contains("curves");
  if (!doc.contains("surfaces") && !constructs) throw root.Error(R"(missing "surfaces")");
  if (doc.contains("surfaces")) {
    const nlohmann::json& surfaces = doc["surfaces"];
    const JsonPlace surfaces_place{name, "surfaces"};
    if (!surfaces.is_array() || surfaces.empty()) {
      throw surfaces_place.Error("must be a non-empty array");
    }
    for (std::size_t i = 0; i < surfaces.size(); ++i) {
      AddSurface(surfaces[i], surfaces_place.Index(i), &set);
    }
  }
  // Constructions and curves (docs/constructions.md), after the surfaces so
  // that a construction can refer to their patches by number.
  if (doc.contains("construct")) AddConstructions(doc["construct"], name, &set);
  if (doc.contains("curves")) AddCurves(doc["curves"], name, &set);
  return set;
}

Basis ParseBasis(const nlohmann::json& value, const JsonPlace& place) {
  if (!value.is_string()) throw place.Error("must be a string");
  const std::string name = value.get<std::string>();
  for (int b = 0; b < kBasisCount; ++b) {
    if (name == BasisName(static_cast<Basis>(b))) return static_cast<Basis>(b);
  }
  throw place.Error("unknown basis '" + name +
                    "' (expected bezier, hermite, bspline, catmull-rom or power)");
}

namespace {

using TextReader = PatchSet (*)(const std::string& text, const std::string& name,
                                const ReadOptions& options);

PatchSet ReadBptFile(const std::string& text, const std::string& name, const ReadOptions&) {
  return ParseBpt(text, name);
}

PatchSet ReadJsonFile(const std::string& text, const std::string& name, const ReadOptions&) {
  return ParseJson(text, name);
}

PatchSet ParseObjMesh(const std::string& text, const std::string& name, const ReadOptions&) {
  return MeshAsPatchSet(ParseObj(text, name), name);
}

PatchSet ParsePlyMesh(const std::string& bytes, const std::string& name, const ReadOptions&) {
  return MeshAsPatchSet(ParsePly(bytes, name), name);
}

PatchSet ReadSvgDrawing(const std::string& text, const std::string& name,
                        const ReadOptions& options) {
  return ReadSvg(text, name, options.svg);
}

PatchSet ReadGcodeProgram(const std::string& text, const std::string& name,
                          const ReadOptions& options) {
  return ReadGcode(text, name, options.gcode);
}

// Every input format: its --input-format name, the suffixes that say it (in
// any case) and its reader; a reader this build does not have is nullptr.
// Adding a format is one row.
struct InputFormat {
  const char* name;
  std::array<const char*, 5> suffixes;
  TextReader read;
};

constexpr InputFormat kInputFormats[] = {
    {"bpt", {".bpt"}, ReadBptFile},
    {"json", {".json"}, ReadJsonFile},
    {"obj", {".obj"}, ParseObjMesh},
    {"ply", {".ply"}, ParsePlyMesh},
    {"svg", {".svg"}, ReadSvgDrawing},
    {"gcode", {".gcode", ".nc", ".ngc", ".g", ".gco"}, ReadGcodeProgram},
};

const InputFormat* FormatNamed(const std::string& name) {
  for (const InputFormat& format : kInputFormats) {
    if (name == format.name) return &format;
  }
  return nullptr;
}

const InputFormat* FormatBySuffix(const std::string& path) {
  std::string lower = path;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const InputFormat& format : kInputFormats) {
    for (const char* suffix : format.suffixes) {
      if (suffix != nullptr && EndsWith(lower, suffix)) return &format;
    }
  }
  return nullptr;
}

// The format by the first characters of the content, for standard input and
// files without a known suffix: '{' JSON, '<' SVG, "ply" PLY, a digit BPT
// (its patch count), an OBJ statement or comment, a G-code word or comment.
const InputFormat* FormatByContent(const std::string& text) {
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return nullptr;
  const std::string_view head = std::string_view(text).substr(first, 4);
  const char c = head[0];
  if (c == '{') return FormatNamed("json");
  if (c == '<') return FormatNamed("svg");
  if (head.substr(0, 3) == "ply") return FormatNamed("ply");
  if (std::isdigit(static_cast<unsigned char>(c)) != 0) return FormatNamed("bpt");
  const std::string_view word = head.substr(0, head.find_first_of(" \t"));
  if (c == '#' || word == "v" || word == "vn" || word == "vt" || word == "f" || word == "o" ||
      word == "g") {
    return FormatNamed("obj");
  }
  if (c == ';' || c == '(' || c == '%' || c == 'G' || c == 'g' || c == 'M' || c == 'N') {
    return FormatNamed("gcode");
  }
  return nullptr;
}

std::string ReadAll(const std::string& path, const std::string& name) {
  std::ostringstream buffer;
  if (path == "-") {
    buffer << std::cin.rdbuf();
    if (std::cin.bad()) throw InputError(name + ": read error");
    return buffer.str();
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path + ": read error");
  return buffer.str();
}

}  // namespace

PatchSet ReadPatchFile(const std::string& path, const std::string& format_name,
                       const ReadOptions& options, std::string* format_read) {
  const std::string name = path == "-" ? "<stdin>" : path;
  const InputFormat* format = nullptr;
  if (!format_name.empty()) {
    format = FormatNamed(format_name);
    if (format == nullptr) {
      throw InputError("--input-format: '" + format_name +
                       "' is not bpt, json, obj, ply, svg or gcode");
    }
  }
  if (format == nullptr && path != "-") format = FormatBySuffix(path);
  const std::string text = ReadAll(path, name);
  if (format == nullptr) {
    if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
      throw InputError(name + ": the " + (path == "-" ? "input" : "file") + " is empty");
    }
    format = FormatByContent(text);
    if (format == nullptr) {
      throw InputError(name +
                       ": cannot tell the format from the content; say it with --input-format "
                       "bpt|json|obj|ply|svg|gcode");
    }
  }
  if (format->read == nullptr) {
    throw InputError(name + ": " + format->name + " input is not available");
  }
  if (format_read != nullptr) *format_read = format->name;
  return format->read(text, name, options);
}

}  // namespace fdsurf::host
