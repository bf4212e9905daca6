// SPDX-License-Identifier: MIT
// The host reference: the same image code as the targets, built with the
// host compiler, printing to stdout. Also writes the prepared tables of the
// ATmega328P image (--emit-tables), from the same set-up code.
//
//   fdsurf_image_host                 the full report (every target but the 328P)
//   fdsurf_image_host --small         the 328P's report
//   fdsurf_image_host --emit-tables F the 328P's tables as C++ source
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "../image/bench.h"
#include "../image/cases.h"
#include "../image/image.h"
#include "../image/port.h"

namespace fdsurf::image {

void PortPutChar(char c) { std::putchar(c); }
void PortReadRom(void* to, const void* from, size_t n) { std::memcpy(to, from, n); }
void PortMark() {}
uint32_t PortStackUsed() { return 0; }
void PortExit(int status) { std::exit(status); }

namespace {

std::string Int128Text(const Int128& v) {
  char text[64];
  std::snprintf(text, sizeof text, "{0x%016" PRIx64 "ull, 0x%016" PRIx64 "ull}", v.lo, v.hi);
  return text;
}

std::string FormatText(const DiffFormat& f) {
  char text[32];
  std::snprintf(text, sizeof text, "{%u, %u, %u}", static_cast<unsigned>(f.acc_bits),
                static_cast<unsigned>(f.frac_bits), static_cast<unsigned>(f.word_aligned));
  return text;
}

std::string Int64Text(int64_t v) {
  // Written as a cast of the unsigned bits, valid for INT64_MIN too.
  char text[48];
  std::snprintf(text, sizeof text, "static_cast<int64_t>(0x%016" PRIx64 "ull)",
                static_cast<uint64_t>(v));
  return text;
}

template <int kDims>
std::string Text(const PreparedPatch<kDims>& p) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, falsely) on "{" + string.
  std::string s = "{";
  s += FormatText(p.format) + ", " + std::to_string(p.steps_s) + ", " + std::to_string(p.steps_t) +
       ", " + (p.exact ? "true" : "false") + ", " + std::to_string(p.s_line_frac_bits) + ", " +
       std::to_string(p.t_line_frac_bits) + ", " + std::to_string(p.s_line_segment_steps) + ", " +
       std::to_string(p.t_line_segment_steps) + ", {";
  for (int c = 0; c < kDims; ++c) {
    s += "{";
    for (int k = 0; k < 4; ++k) {
      s += "{";
      for (int l = 0; l < 4; ++l) s += Int128Text(p.dd[c][k][l]) + ", ";
      s += "}, ";
    }
    s += "}, ";
  }
  return s + "}}";
}

template <int kDims>
std::string Text(const PreparedCurve<kDims>& p) {
  std::string s = "{";
  s += FormatText(p.format) + ", " + std::to_string(p.steps) + ", " + (p.exact ? "true" : "false") +
       ", {";
  for (int c = 0; c < kDims; ++c) {
    s += "{";
    for (int k = 0; k < 4; ++k) s += Int128Text(p.d[c][k]) + ", ";
    s += "}, ";
  }
  return s + "}}";
}

template <int kDims>
std::string Text(const PreparedAdaptiveCurve<kDims>& p) {
  std::string s = "{";
  s += FormatText(p.format) + ", " + std::to_string(p.finest_level) +
       ", static_cast<AdaptiveMode>(" + std::to_string(static_cast<int>(p.mode)) + "), {";
  for (int c = 0; c < kDims; ++c) {
    s += "{";
    for (int k = 0; k < 4; ++k) s += Int128Text(p.d[c][k]) + ", ";
    s += "}, ";
  }
  return s + "}, " + Int128Text(p.chord_limit) + ", " + Int128Text(p.step_limit) + "}";
}

std::string Head(const char* name, uint16_t index) {
  return "{\"" + std::string(name) + "\", " + std::to_string(index) + ", ";
}

std::string StatusText(Status status) {
  return "static_cast<Status>(" + std::to_string(static_cast<int>(status)) + "), ";
}

// Visits the small set (as the Reporter does) and collects it as C++ text.
struct TableWriter {
  std::vector<std::string> patch2, curve2, curve3, adaptive2, coefficients2, order;

  void Add(std::vector<std::string>& list, const char* kind, std::string item) {
    order.push_back(std::string("{RomKind::") + kind + ", " + std::to_string(list.size()) + "}");
    list.push_back(std::move(item));
  }
  template <int kDims>
  void Patch(bool small, const char* name, uint16_t index, Status status,
             const PreparedPatch<kDims>& p) {
    if (!small) return;
    static_assert(kDims == 2 || kDims == 3);
    if constexpr (kDims == 2) {
      Add(patch2, "kPatch2", Head(name, index) + StatusText(status) + Text(p) + "}");
    } else {
      std::fprintf(stderr, "no 3-D patches in the small set\n");
      std::exit(2);
    }
  }
  template <int kDims>
  void Curve(bool small, const char* name, uint16_t index, Status status,
             const PreparedCurve<kDims>& p) {
    if (!small) return;
    Add(kDims == 2 ? curve2 : curve3, kDims == 2 ? "kCurve2" : "kCurve3",
        Head(name, index) + StatusText(status) + Text(p) + "}");
  }
  template <int kDims>
  void Adaptive(bool small, const char* name, uint16_t index, Status status,
                const PreparedAdaptiveCurve<kDims>& p) {
    if (!small) return;
    if constexpr (kDims == 2) {
      Add(adaptive2, "kAdaptive2", Head(name, index) + StatusText(status) + Text(p) + "}");
    } else {
      std::fprintf(stderr, "no 3-D adaptive curves in the small set\n");
      std::exit(2);
    }
  }
  template <int kDims>
  void Coefficients(bool small, const char* name, uint16_t index,
                    const PowerCurve1 (&curve)[kDims]) {
    if (!small) return;
    std::string s = Head(name, index) + "{";
    for (int c = 0; c < kDims; ++c) {
      s += "{{";
      for (int k = 0; k < 4; ++k) s += Int64Text(curve[c].c[k]) + ", ";
      s += "}}, ";
    }
    Add(coefficients2, "kCoefficients2", s + "}}");
  }
};

void WriteArray(std::FILE* out, const char* type, const char* name,
                const std::vector<std::string>& items) {
  std::fprintf(out, "const %s %s[] FDSURF_IMAGE_ROM = {\n", type, name);
  for (const auto& item : items) std::fprintf(out, "    %s,\n", item.c_str());
  if (items.empty()) std::fprintf(out, "    {},\n");
  std::fprintf(out, "};\n");
}

int EmitTables(const char* path) {
  TableWriter writer;
  RunCases(writer);
  PreparedCurve<2> curve2[2];
  SetupBenchCurve2(false, &curve2[0]);
  SetupBenchCurve2(true, &curve2[1]);
  PreparedCurve<3> curve3;
  SetupBenchCurve3(&curve3);
  PreparedPatch<2> patch2;
  SetupBenchPatch2(&patch2);
  PreparedAdaptiveCurve<2> adaptive2;
  SetupBenchAdaptive2(&adaptive2);

  std::FILE* out = std::fopen(path, "w");
  if (out == nullptr) {
    std::perror(path);
    return 1;
  }
  std::fprintf(out,
               "// Generated by fdsurf_image_host --emit-tables (targets/port/host.cc): the\n"
               "// small set, prepared on the host. Do not edit.\n"
               "#include \"rom_tables.h\"\n#include \"port.h\"\n\n"
               "namespace fdsurf {\nnamespace image {\n\n");
  WriteArray(out, "RomPatch2", "kRomPatch2", writer.patch2);
  WriteArray(out, "RomCurve2", "kRomCurve2", writer.curve2);
  WriteArray(out, "RomCurve3", "kRomCurve3", writer.curve3);
  WriteArray(out, "RomAdaptive2", "kRomAdaptive2", writer.adaptive2);
  WriteArray(out, "RomCoefficients2", "kRomCoefficients2", writer.coefficients2);
  WriteArray(out, "RomItem", "kRomOrder", writer.order);
  std::fprintf(out, "const uint16_t kRomOrderCount = %zu;\n", writer.order.size());
  std::fprintf(out, "const PreparedCurve<2> kRomBenchCurve2[2] FDSURF_IMAGE_ROM = {%s, %s};\n",
               Text(curve2[0]).c_str(), Text(curve2[1]).c_str());
  std::fprintf(out, "const PreparedCurve<3> kRomBenchCurve3 FDSURF_IMAGE_ROM = %s;\n",
               Text(curve3).c_str());
  std::fprintf(out, "const PreparedPatch<2> kRomBenchPatch2 FDSURF_IMAGE_ROM = %s;\n",
               Text(patch2).c_str());
  std::fprintf(out, "const PreparedAdaptiveCurve<2> kRomBenchAdaptive2 FDSURF_IMAGE_ROM = %s;\n",
               Text(adaptive2).c_str());
  std::fprintf(out, "\n}  // namespace image\n}  // namespace fdsurf\n");
  return std::fclose(out) == 0 ? 0 : 1;
}

}  // namespace
}  // namespace fdsurf::image

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "--emit-tables") == 0) {
    return fdsurf::image::EmitTables(argv[2]);
  }
  const bool small = argc == 2 && std::strcmp(argv[1], "--small") == 0;
  if (argc > 1 && !small) {
    std::fprintf(stderr, "usage: fdsurf_image_host [--small | --emit-tables FILE]\n");
    return 2;
  }
  return fdsurf::image::RunImage(small);
}
