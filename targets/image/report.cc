#include "report.h"

namespace fdsurf {
namespace image {

void PutString(const char* text) {
  while (*text != '\0') PortPutChar(*text++);
}

void PutUnsigned(uint32_t value) {
  char digits[10];
  int n = 0;
  do {
    digits[n++] = static_cast<char>('0' + value % 10u);
    value /= 10u;
  } while (value != 0);
  while (n > 0) PortPutChar(digits[--n]);
}

void PutDecimal(int32_t value) {
  if (value < 0) {
    PortPutChar('-');
    PutUnsigned(0u - static_cast<uint32_t>(value));
  } else {
    PutUnsigned(static_cast<uint32_t>(value));
  }
}

void PutHex(uint32_t value) {
  for (int shift = 28; shift >= 0; shift -= 4) {
    PortPutChar("0123456789abcdef"[(value >> shift) & 0xFu]);
  }
}

void PutItemHead(const char* kind, const char* name, uint16_t index, Status status,
                 const DiffFormat& format) {
  PutString(kind);
  PutString(" ");
  PutString(name);
  PutString("-");
  PutUnsigned(index);
  PutString(status == Status::kOk ? " ok" : " refused ");
  if (status != Status::kOk) {
    PutUnsigned(static_cast<uint32_t>(status));
    return;
  }
  PutString(" acc ");
  PutUnsigned(format.acc_bits);
  PutString(" frac ");
  PutUnsigned(format.frac_bits);
}

namespace {

template <typename Acc, int kDims>
void DigestPatch(const PreparedPatch<kDims>& patch) {
  PointDigest<kDims> s_lines;
  PointDigest<kDims> t_lines;
  const PatchStepper<Acc, kDims> stepper(patch);
  stepper.ForEachSLinePoint(
      [&s_lines](uint32_t, uint32_t, const int32_t(&point)[kDims]) { s_lines.Add(point); });
  stepper.ForEachTLinePoint(
      [&t_lines](uint32_t, uint32_t, const int32_t(&point)[kDims]) { t_lines.Add(point); });
  s_lines.Put();
  PutString(" tlines");
  t_lines.Put();
}

template <typename Acc, int kDims>
void DigestCurve(const PreparedCurve<kDims>& curve) {
  PointDigest<kDims> digest;
  CurveStepper<Acc, kDims>(curve).ForEachPoint(
      [&digest](uint32_t, const int32_t(&point)[kDims]) { digest.Add(point); });
  digest.Put();
}

template <typename Acc, int kDims>
void DigestAdaptive(const PreparedAdaptiveCurve<kDims>& curve) {
  PointDigest<kDims> digest;
  // The parameter positions are part of the result too: fold them in as a
  // further "coordinate" digest.
  PointDigest<1> positions;
  AdaptiveCurveStepper<Acc, kDims>(curve).ForEachPoint(
      [&digest, &positions](uint32_t position, const int32_t(&point)[kDims]) {
        digest.Add(point);
        const int32_t p[1] = {static_cast<int32_t>(position)};
        positions.Add(p);
      });
  digest.Put();
  PutString(" positions");
  positions.Put();
}

}  // namespace

template <int kDims>
void Reporter::Patch(bool small, const char* name, uint16_t index, Status status,
                     const PreparedPatch<kDims>& patch) {
  if (small_only && !small) return;
  PutItemHead(kDims == 2 ? "patch2" : "patch3", name, index, status, patch.format);
  if (status == Status::kOk) {
    PutString(patch.exact ? " exact" : " rounded");
    if (patch.format.acc_bits == 64) {
      DigestPatch<int64_t>(patch);
    } else {
      DigestPatch<Int128>(patch);
    }
  }
  PutString("\n");
}

template <int kDims>
void Reporter::Curve(bool small, const char* name, uint16_t index, Status status,
                     const PreparedCurve<kDims>& curve) {
  if (small_only && !small) return;
  PutItemHead(kDims == 2 ? "curve2" : "curve3", name, index, status, curve.format);
  if (status == Status::kOk) {
    PutString(curve.exact ? " exact" : " rounded");
    if (curve.format.acc_bits == 64) {
      DigestCurve<int64_t>(curve);
    } else {
      DigestCurve<Int128>(curve);
    }
  }
  PutString("\n");
}

template <int kDims>
void Reporter::Adaptive(bool small, const char* name, uint16_t index, Status status,
                        const PreparedAdaptiveCurve<kDims>& curve) {
  if (small_only && !small) return;
  PutItemHead(kDims == 2 ? "adaptive2" : "adaptive3", name, index, status, curve.format);
  if (status == Status::kOk) {
    PutString(" level ");
    PutUnsigned(curve.finest_level);
    if (curve.format.acc_bits == 64) {
      DigestAdaptive<int64_t>(curve);
    } else {
      DigestAdaptive<Int128>(curve);
    }
  }
  PutString("\n");
}

template <int kDims>
void Reporter::Coefficients(bool small, const char* name, uint16_t index,
                            const PowerCurve1 (&curve)[kDims]) {
  if (small_only && !small) return;
  PutString("coefficients ");
  PutString(name);
  PutString("-");
  PutUnsigned(index);
  PointDigest<1> digest;
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 4; ++k) {
      const uint64_t bits = static_cast<uint64_t>(curve[c].c[k]);
      const int32_t words[2][1] = {{static_cast<int32_t>(static_cast<uint32_t>(bits))},
                                   {static_cast<int32_t>(static_cast<uint32_t>(bits >> 32))}};
      digest.Add(words[0]);
      digest.Add(words[1]);
    }
  }
  digest.Put();
  PutString("\n");
}

// Unused instantiations are dropped by --gc-sections on the targets.
template void Reporter::Patch<2>(bool, const char*, uint16_t, Status, const PreparedPatch<2>&);
template void Reporter::Patch<3>(bool, const char*, uint16_t, Status, const PreparedPatch<3>&);
template void Reporter::Curve<2>(bool, const char*, uint16_t, Status, const PreparedCurve<2>&);
template void Reporter::Curve<3>(bool, const char*, uint16_t, Status, const PreparedCurve<3>&);
template void Reporter::Adaptive<2>(bool, const char*, uint16_t, Status,
                                    const PreparedAdaptiveCurve<2>&);
template void Reporter::Adaptive<3>(bool, const char*, uint16_t, Status,
                                    const PreparedAdaptiveCurve<3>&);
template void Reporter::Coefficients<2>(bool, const char*, uint16_t, const PowerCurve1 (&)[2]);
template void Reporter::Coefficients<3>(bool, const char*, uint16_t, const PowerCurve1 (&)[3]);

}  // namespace image
}  // namespace fdsurf
