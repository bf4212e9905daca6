// SPDX-License-Identifier: MIT
#include "fdsurf/host/writers.h"
#include "fdsurf/host/text.h"

#include <cairo.h>

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

}  // namespace

std::string WriteSvg(const Toolpath& path, const std::string& title) {
  const Quantum& q = path.quantum;
  const std::int64_t w = PageQuanta(path.width, q);
  const std::int64_t h = PageQuanta(path.height, q);
  const std::string width = q.Format(w);
  const std::string height = q.Format(h);
  const double pen = path.units == "in" ? 0.01 : 0.25;
  std::ostringstream out;
  out << R"(<?xml version="1.0" encoding="UTF-8"?>)"
      << "\n"
      << R"(<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width=")" << width << path.units
      << R"(" height=")" << height << path.units << R"(" viewBox="0 0 )" << width << " " << height
      << "\">\n"
      << "<title>" << XmlEscaped(title) << "</title>\n"
      << R"(<g fill="none" stroke="black" stroke-width=")" << FormatNumber(pen)
      << R"(" stroke-linecap="round" stroke-linejoin="round">)"
      << "\n";
  for (const Stroke& s : path.strokes) {
    out << "<path d=\"";
    for (std::size_t k = 0; k < s.points.size(); ++k) {
      out << (k == 0 ? "M" : " L") << q.Format(s.points[k][0]) << " "
          << q.Format(h - s.points[k][1]);
    }
    out << "\"/>\n";
  }
  out << "</g>\n</svg>\n";
  return out.str();
}

std::string WriteGcode(const Toolpath& path, const GcodeOptions& options,
                       const std::vector<std::string>& header) {
  const Quantum& q = path.quantum;
  const bool three_d = path.dims == 3;
  const bool z_pen = options.pen == "z";
  std::ostringstream out;
  for (const std::string& line : header) out << "; " << line << "\n";
  out << (path.units == "in" ? "G20" : "G21") << " ; units: " << path.units << "\n"
      << "G90 ; absolute positions\n";
  const auto pen_up = [&] {
    if (z_pen || three_d) {
      out << "G0 Z" << FormatNumber(options.pen_up_z) << "\n";
    } else {
      out << "M5\nG4 P" << FormatNumber(options.dwell) << "\n";
    }
  };
  pen_up();
  for (const Stroke& s : path.strokes) {
    const auto& first = s.points.front();
    out << "G0 X" << q.Format(first[0]) << " Y" << q.Format(first[1]) << "\n";
    if (three_d) {
      out << "G1 Z" << q.Format(first[2]) << " F" << FormatNumber(options.plunge_feed) << "\n";
    } else if (z_pen) {
      out << "G1 Z" << FormatNumber(options.pen_down_z) << " F" << FormatNumber(options.plunge_feed)
          << "\n";
    } else {
      out << "M3 S" << options.power << "\nG4 P" << FormatNumber(options.dwell) << "\n";
    }
    for (std::size_t k = 1; k < s.points.size(); ++k) {
      out << "G1 X" << q.Format(s.points[k][0]) << " Y" << q.Format(s.points[k][1]);
      if (three_d) out << " Z" << q.Format(s.points[k][2]);
      if (k == 1) out << " F" << FormatNumber(options.feed);
      out << "\n";
    }
    pen_up();
  }
  out << "G0 X0 Y0\nM2\n";
  return out.str();
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
  const double scale = width_px / path.width;
  const int height_px = std::max(1, static_cast<int>(std::ceil(path.height * scale)));
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, height_px);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_set_source_rgb(cr, 0.05, 0.1, 0.3);
  cairo_set_line_width(cr, std::max(1.0, width_px / 1200.0));
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  const double q = path.quantum.value();
  for (const Stroke& s : path.strokes) {
    for (std::size_t k = 0; k < s.points.size(); ++k) {
      const double x = s.points[k][0] * q * scale;
      const double y = height_px - s.points[k][1] * q * scale;
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
