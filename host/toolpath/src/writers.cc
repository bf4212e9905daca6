// SPDX-License-Identifier: MIT
#include "fdsurf/host/writers.h"
#include "fdsurf/host/gcode_estimate.h"
#include "fdsurf/host/text.h"

#include <cairo.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>

namespace fdsurf::host {
namespace {

// The page size in whole quanta, so that flipped coordinates stay exact.
std::int64_t PageQuanta(double size, const Quantum& q) {
  return static_cast<std::int64_t>(std::ceil(q.ToQuanta(size) - 1e-9));
}

// The SVG's pen: 0.25 mm, or 0.01 in.
double PenWidth(const std::string& units) { return units == "in" ? 0.01 : 0.25; }

std::string XmlEscaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string LayerName(const Toolpath& path, const Stroke& s) {
  const auto index = static_cast<std::size_t>(std::max(0, s.layer));
  return index < path.layers.size() ? path.layers[index] : "layer " + std::to_string(s.layer);
}

// What a G-code dialect has (docs/toolpaths.md, "G-code flavours").
struct Flavor {
  std::string name;
  bool has_g5 = false;          // G5 I J P Q X Y cubics
  bool has_m280 = false;        // servo pen
  bool dwell_ms = false;        // G4 P is milliseconds (Marlin), else seconds
  bool paren_comments = false;  // (comment) rather than ; comment
  bool needs_g17 = false;       // G5 only in the XY plane, selected by G17
};

Flavor FlavorNamed(const std::string& name) {
  if (name == "generic") return Flavor{name};
  if (name == "grbl") return Flavor{name, false, false, false, true, false};
  if (name == "marlin") return Flavor{name, true, true, true, false, false};
  if (name == "linuxcnc") return Flavor{name, true, false, false, true, true};
  throw OptionError("flavor", name, "is not one of generic, grbl, marlin, linuxcnc");
}

using QuantaPoint = std::array<std::int64_t, 2>;

// Writes one program; every choice a flavour makes is in Flavor.
class GcodeWriter {
 public:
  GcodeWriter(const Toolpath& path, const GcodeOptions& options)
      : path_(path),
        options_(options),
        flavor_(FlavorNamed(options.flavor)),
        q_(path.quantum),
        three_d_(path.dims == 3),
        pen_(three_d_ ? "z" : options.pen) {
    if (pen_ != "z" && pen_ != "m3" && pen_ != "servo") {
      throw OptionError("pen", options.pen, "is not one of z, m3, servo");
    }
    if (pen_ == "servo" && !flavor_.has_m280) {
      throw OptionError(
          "pen", "servo",
          "needs M280 (Marlin); the flavour " + flavor_.name + " has no servo command");
    }
    use_g5_ = flavor_.has_g5 && options.g5 && !three_d_;
  }

  std::string Write(const std::vector<std::string>& header) {
    for (const std::string& line : header) Comment(line);
    if (flavor_.name != "generic") {
      Comment("flavor " + flavor_.name + (use_g5_ ? ", cubics as G5" : ", cubics as G1 segments") +
              ", dwell G4 P in " + (flavor_.dwell_ms ? "milliseconds" : "seconds"));
    }
    if (flavor_.name != "generic" || options_.estimate_in_header) {
      const GcodeEstimate estimate = EstimateGcode(path_, options_);
      for (const std::string& line : DescribeGcodeEstimate(estimate, options_, path_.units)) {
        Comment(line);
      }
    }
    out_ << (path_.units == "in" ? "G20" : "G21") << Trailing("units: " + path_.units) << "\n"
         << "G90" << Trailing("absolute positions") << "\n";
    if (flavor_.needs_g17 && use_g5_) out_ << "G17" << Trailing("XY plane, for G5") << "\n";
    PenUp();
    int layer = -1;
    for (const Stroke& s : path_.strokes) {
      if (!path_.layers.empty() && s.layer != layer) {
        if (layer >= 0) {
          Comment("pen change: layer '" + LayerName(path_, s) + "'");
          out_ << "M0\n";
        } else {
          Comment("layer '" + LayerName(path_, s) + "'");
        }
        layer = s.layer;
      }
      if (use_g5_ && !s.cubics.empty()) {
        WriteCubics(s);
      } else {
        WriteSegments(s);
      }
      PenUp();
    }
    out_ << "G0 X0 Y0\nM2\n";
    return out_.str();
  }

 private:
  // A comment line in the flavour's syntax.
  void Comment(const std::string& text) {
    if (flavor_.paren_comments) {
      out_ << "(" << Parenless(text) << ")\n";
    } else {
      out_ << "; " << text << "\n";
    }
  }

  // A comment after a command on the same line.
  std::string Trailing(const std::string& text) const {
    return flavor_.paren_comments ? " (" + Parenless(text) + ")" : " ; " + text;
  }

  // Parenthesised comments cannot nest: inner parentheses become brackets.
  static std::string Parenless(std::string text) {
    for (char& c : text) {
      if (c == '(') c = '[';
      if (c == ')') c = ']';
    }
    return text;
  }

  void Dwell() {
    if (flavor_.dwell_ms) {
      out_ << "G4 P" << std::llround(options_.dwell * 1000) << "\n";
    } else {
      out_ << "G4 P" << FormatNumber(options_.dwell) << "\n";
    }
  }

  void PenUp() {
    if (pen_ == "z") {
      out_ << "G0 Z" << FormatNumber(options_.pen_up_z) << "\n";
    } else if (pen_ == "m3") {
      out_ << "M5\n";
      Dwell();
    } else {
      out_ << "M280 P" << options_.servo_index << " S" << FormatNumber(options_.servo_up) << "\n";
      Dwell();
    }
  }

  void PenDown(const std::array<std::int64_t, 3>& first) {
    if (three_d_) {
      out_ << "G1 Z" << q_.Format(first[2]) << " F" << FormatNumber(options_.plunge_feed) << "\n";
    } else if (pen_ == "z") {
      out_ << "G1 Z" << FormatNumber(options_.pen_down_z) << " F"
           << FormatNumber(options_.plunge_feed) << "\n";
    } else if (pen_ == "m3") {
      out_ << "M3 S" << options_.power << "\n";
      Dwell();
    } else {
      out_ << "M280 P" << options_.servo_index << " S" << FormatNumber(options_.servo_down) << "\n";
      Dwell();
    }
  }

  void WriteSegments(const Stroke& s) {
    const auto& first = s.points.front();
    out_ << "G0 X" << q_.Format(first[0]) << " Y" << q_.Format(first[1]) << "\n";
    PenDown(first);
    for (std::size_t k = 1; k < s.points.size(); ++k) {
      out_ << "G1 X" << q_.Format(s.points[k][0]) << " Y" << q_.Format(s.points[k][1]);
      if (three_d_) out_ << " Z" << q_.Format(s.points[k][2]);
      if (k == 1) out_ << " F" << FormatNumber(options_.feed);
      out_ << "\n";
    }
  }

  QuantaPoint Rounded(const std::array<double, 3>& p) const {
    return {std::llround(q_.ToQuanta(p[0])), std::llround(q_.ToQuanta(p[1]))};
  }

  // Distance in output units between a printed point and the exact one.
  double Error(const QuantaPoint& printed, const std::array<double, 3>& exact) const {
    return std::hypot(printed[0] * q_.value() - exact[0], printed[1] * q_.value() - exact[1]);
  }

  // Each piece as G5 from the current position: I J = first control point −
  // start, P Q = second control point − end (Marlin's and LinuxCNC's words).
  void WriteCubics(const Stroke& s) {
    QuantaPoint at = Rounded(s.cubics.front()[0]);
    out_ << "G0 X" << q_.Format(at[0]) << " Y" << q_.Format(at[1]) << "\n";
    PenDown(s.points.front());
    bool first = true;
    for (const auto& cubic : s.cubics) {
      const QuantaPoint c1 = Rounded(cubic[1]);
      const QuantaPoint c2 = Rounded(cubic[2]);
      const QuantaPoint end = Rounded(cubic[3]);
      // Convex hull: the printed curve is within the largest control-point
      // error of the exact one (docs/toolpaths.md, "G5 and the quantum").
      const double error = std::max(
          {Error(at, cubic[0]), Error(c1, cubic[1]), Error(c2, cubic[2]), Error(end, cubic[3])});
      if (path_.tolerance > 0 && error > path_.tolerance) {
        throw OptionError("tolerance", FormatNumber(path_.tolerance) + " " + path_.units,
                          "is smaller than the " + FormatNumber(error) + " " + path_.units +
                              " that G5 control points printed at the quantum " + q_.Format(1) +
                              " move a curve; use a larger tolerance or G1 segments (--no-g5)");
      }
      if (c1 == at && c2 == at && end == at) continue;  // draws nothing
      out_ << "G5 I" << q_.Format(c1[0] - at[0]) << " J" << q_.Format(c1[1] - at[1]) << " P"
           << q_.Format(c2[0] - end[0]) << " Q" << q_.Format(c2[1] - end[1]) << " X"
           << q_.Format(end[0]) << " Y" << q_.Format(end[1]);
      if (first) out_ << " F" << FormatNumber(options_.feed);
      out_ << "\n";
      first = false;
      at = end;
    }
  }

  const Toolpath& path_;
  const GcodeOptions& options_;
  Flavor flavor_;
  const Quantum& q_;
  bool three_d_;
  std::string pen_;
  bool use_g5_ = false;
  std::ostringstream out_;
};

}  // namespace

PageView ViewOfPage(const Toolpath& path) {
  const Quantum& q = path.quantum;
  const std::array<std::int64_t, 2> page{PageQuanta(path.width, q), PageQuanta(path.height, q)};
  PageView view{{0, 0}, page, false};
  std::array<std::int64_t, 2> lo{0, 0};
  std::array<std::int64_t, 2> hi = page;
  for (const Stroke& s : path.strokes) {
    for (const auto& p : s.points) {
      for (int c = 0; c < 2; ++c) {
        lo[c] = std::min(lo[c], p[c]);
        hi[c] = std::max(hi[c], p[c]);
      }
    }
  }
  // Half the pen beyond the outermost point, so that its line is whole too.
  const std::int64_t half_pen = PageQuanta(PenWidth(path.units) / 2, q);
  for (int c = 0; c < 2; ++c) {
    if (lo[c] < 0) view.lo[c] = lo[c] - half_pen;
    if (hi[c] > page[c]) view.hi[c] = hi[c] + half_pen;
  }
  view.past_page = view.lo[0] < 0 || view.lo[1] < 0 || view.hi != page;
  return view;
}

std::string WriteSvg(const Toolpath& path, const std::string& title) {
  const Quantum& q = path.quantum;
  // User units are output units with y flipped at the page's top edge h,
  // whatever the view: a point's coordinates do not depend on the view box.
  const std::int64_t h = PageQuanta(path.height, q);
  const PageView view = ViewOfPage(path);
  const std::string width = q.Format(view.hi[0] - view.lo[0]);
  const std::string height = q.Format(view.hi[1] - view.lo[1]);
  // The page alone keeps the "0 0 W H" it always had.
  const auto origin = [&q](std::int64_t v) { return v == 0 ? std::string("0") : q.Format(v); };
  const bool layered = !path.layers.empty();
  std::ostringstream out;
  out << R"(<?xml version="1.0" encoding="UTF-8"?>)"
      << "\n"
      << R"(<svg xmlns="http://www.w3.org/2000/svg" )"
      << (layered ? R"(xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" )" : "")
      << R"(version="1.1" width=")" << width << path.units << R"(" height=")" << height
      << path.units << R"(" viewBox=")" << origin(view.lo[0]) << " " << origin(h - view.hi[1])
      << " " << width << " " << height << "\">\n"
      << "<title>" << XmlEscaped(title) << "</title>\n"
      << R"(<g fill="none" stroke="black" stroke-width=")" << FormatNumber(PenWidth(path.units))
      << R"(" stroke-linecap="round" stroke-linejoin="round">)"
      << "\n";
  int open_layer = -1;  // the layer group being written, -1 for none
  for (const Stroke& s : path.strokes) {
    if (layered && s.layer != open_layer) {
      if (open_layer >= 0) out << "</g>\n";
      open_layer = s.layer;
      out << R"(<g inkscape:groupmode="layer" inkscape:label=")" << XmlEscaped(LayerName(path, s))
          << "\">\n";
    }
    out << "<path d=\"";
    for (std::size_t k = 0; k < s.points.size(); ++k) {
      out << (k == 0 ? "M" : " L") << q.Format(s.points[k][0]) << " "
          << q.Format(h - s.points[k][1]);
    }
    out << "\"/>\n";
  }
  if (open_layer >= 0) out << "</g>\n";
  out << "</g>\n</svg>\n";
  return out.str();
}

std::string WriteGcode(const Toolpath& path, const GcodeOptions& options,
                       const std::vector<std::string>& header) {
  return GcodeWriter(path, options).Write(header);
}

double EstimateGcodeSeconds(const Toolpath& path, const GcodeOptions& options) {
  (void)GcodeWriter(path, options);  // the writer's checks
  return EstimateGcode(path, options).seconds;
}

std::string WriteHpgl(const Toolpath& path) {
  if (!(path.quantum.mantissa() == 25 && path.quantum.decimals() == 3 && path.units == "mm")) {
    throw OutputError("HPGL needs points in plotter units (quantum 0.025 mm)");
  }
  std::ostringstream out;
  out << "IN;SP1;\n";
  for (const Stroke& s : path.strokes) {
    out << "PU" << s.points[0][0] << "," << s.points[0][1] << ";";
    if (s.points.size() > 1) {
      out << "PD";
      for (std::size_t k = 1; k < s.points.size(); ++k) {
        out << (k == 1 ? "" : ",") << s.points[k][0] << "," << s.points[k][1];
      }
      out << ";";
    } else {
      out << "PD;";  // a one-point stroke is a dot
    }
    out << "\n";
  }
  out << "PU;SP0;\n";
  return out.str();
}

std::string WriteStrokesJson(const Toolpath& path) {
  const Quantum& q = path.quantum;
  std::array<std::int64_t, 3> lo{INT64_MAX, INT64_MAX, INT64_MAX};
  std::array<std::int64_t, 3> hi{INT64_MIN, INT64_MIN, INT64_MIN};
  for (const Stroke& s : path.strokes) {
    for (const auto& p : s.points) {
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], p[c]);
        hi[c] = std::max(hi[c], p[c]);
      }
    }
  }
  std::ostringstream out;
  const auto point = [&](const std::array<std::int64_t, 3>& p) {
    out << "[" << q.Format(p[0]) << "," << q.Format(p[1]);
    if (path.dims == 3) out << "," << q.Format(p[2]);
    out << "]";
  };
  out << R"({"units":")" << path.units << R"(","quantum":)" << q.Format(1)
      << ",\"dims\":" << path.dims << ",\"width\":" << q.Format(PageQuanta(path.width, q))
      << ",\"height\":" << q.Format(PageQuanta(path.height, q)) << ",\"bbox\":[";
  if (path.dims == 3) {
    out << q.Format(lo[0]) << "," << q.Format(lo[1]) << "," << q.Format(lo[2]) << ","
        << q.Format(hi[0]) << "," << q.Format(hi[1]) << "," << q.Format(hi[2]);
  } else {
    out << q.Format(lo[0]) << "," << q.Format(lo[1]) << "," << q.Format(hi[0]) << ","
        << q.Format(hi[1]);
  }
  out << "],\"strokes\":[";
  for (std::size_t i = 0; i < path.strokes.size(); ++i) {
    out << (i == 0 ? "\n[" : ",\n[");
    const auto& points = path.strokes[i].points;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (k > 0) out << ",";
      point(points[k]);
    }
    out << "]";
  }
  out << "]}\n";
  return out.str();
}

void RenderPng(const Toolpath& path, int width_px, const std::string& file) {
  const double q = path.quantum.value();
  const PageView view = ViewOfPage(path);
  const std::int64_t wide = view.hi[0] - view.lo[0];
  const std::int64_t high = view.hi[1] - view.lo[1];
  const double scale = width_px / (static_cast<double>(wide) * q);  // pixels per unit
  // The height in proportion, rounded up in integers (no ceil of 366.0000001).
  const int height_px = std::max<int>(1, static_cast<int>((high * width_px + wide - 1) / wide));
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, height_px);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_set_source_rgb(cr, 0.05, 0.1, 0.3);
  cairo_set_line_width(cr, std::max(1.0, width_px / 1200.0));
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  for (const Stroke& s : path.strokes) {
    for (std::size_t k = 0; k < s.points.size(); ++k) {
      const double x = static_cast<double>(s.points[k][0] - view.lo[0]) * q * scale;
      const double y = height_px - static_cast<double>(s.points[k][1] - view.lo[1]) * q * scale;
      if (k == 0) {
        cairo_move_to(cr, x, y);
      } else {
        cairo_line_to(cr, x, y);
      }
    }
    cairo_stroke(cr);
  }
  cairo_destroy(cr);
  const cairo_status_t status = cairo_surface_write_to_png(surface, file.c_str());
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw OutputError(file + ": cannot write the PNG: " + cairo_status_to_string(status));
  }
}

void WriteFile(const std::string& file, const std::string& content) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (f == nullptr) throw OutputError(file + ": cannot write: " + std::strerror(errno));
  const bool written = std::fwrite(content.data(), 1, content.size(), f) == content.size();
  const int write_errno = errno;
  if (std::fclose(f) != 0 || !written) {
    throw OutputError(file + ": cannot write: " + std::strerror(written ? errno : write_errno));
  }
}

}  // namespace fdsurf::host
