// SPDX-License-Identifier: MIT
#include "report.h"

namespace fdsurf {
namespace image {

// kCrcNibbleTable[n] is the CRC-32 (polynomial 0xEDB88320) of the nibble n
// shifted through four steps of the bitwise algorithm.
const uint32_t kCrcNibbleTable[16] = {0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu,
                                      0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
                                      0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
                                      0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu};

void PutString(const char* text) {
  for (;;) {
    char c;
    PortReadRom(&c, text++, 1);
    if (c == '\0') return;
    PortPutChar(c);
  }
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
    const uint8_t nibble = static_cast<uint8_t>((value >> shift) & 0xFu);
    PortPutChar(static_cast<char>(nibble < 10 ? '0' + nibble : 'a' + nibble - 10));
  }
}

void PutItemHead(const char* kind, const char* name, uint16_t index, Status status,
                 const DiffFormat& format) {
  PutString(kind);
  PutString(FDSURF_TEXT(" "));
  PutString(name);
  PutString(FDSURF_TEXT("-"));
  PutUnsigned(index);
  PutString(status == Status::kOk ? FDSURF_TEXT(" ok") : FDSURF_TEXT(" refused "));
  if (status != Status::kOk) {
    PutUnsigned(static_cast<uint32_t>(status));
    return;
  }
  PutString(FDSURF_TEXT(" acc "));
  PutUnsigned(format.acc_bits);
  PutString(FDSURF_TEXT(" frac "));
  PutUnsigned(format.frac_bits);
}

namespace {

volatile int32_t g_adaptive_sink[3];

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
  PutString(FDSURF_TEXT(" tlines"));
  t_lines.Put();
}

template <typename Acc, int kDims>
void DigestCurve(const PreparedCurve<kDims>& curve) {
  PointDigest<kDims> digest;
  CurveStepper<Acc, kDims>(curve).ForEachPoint(
      [&digest](uint32_t, const int32_t(&point)[kDims]) { digest.Add(point); });
  digest.Put();
}

template <int kDims>
void DigestAdaptive(const PreparedAdaptiveCurve<kDims>& curve) {
  PointDigest<kDims> digest;
  // The parameter positions are part of the result too: a further digest.
  PointDigest<1> positions;
  StepAdaptive(curve, &digest, &positions);
  digest.Put();
  PutString(FDSURF_TEXT(" positions"));
  positions.Put();
}

// What the adaptive stepper calls per point: a store that cannot be
// optimized away and, for the report, the digests.
template <int kDims>
struct AdaptiveSink {
  PointDigest<kDims>* points;
  PointDigest<1>* positions;
  uint32_t count;
  void operator()(uint32_t position, const int32_t (&point)[kDims]) {
    for (int c = 0; c < kDims; ++c) g_adaptive_sink[c] = point[c];
    ++count;
    if (points != nullptr) {
      points->Add(point);
      const int32_t p[1] = {static_cast<int32_t>(position)};
      positions->Add(p);
    }
  }
};

}  // namespace

template <int kDims>
uint32_t StepAdaptive(const PreparedAdaptiveCurve<kDims>& curve, PointDigest<kDims>* points,
                      PointDigest<1>* positions) {
  AdaptiveSink<kDims> sink{points, positions, 0};
  if (curve.format.acc_bits == 64) {
    AdaptiveCurveStepper<int64_t, kDims>(curve).ForEachPoint(sink);
  } else if (kImageWideAccumulators) {
    AdaptiveCurveStepper<Int128, kDims>(curve).ForEachPoint(sink);
  } else {
    PortExit(4);
  }
  return sink.count;
}

template <int kDims>
void Reporter::Patch(bool small, const char* name, uint16_t index, Status status,
                     const PreparedPatch<kDims>& patch) {
  if (small_only && !small) return;
  PutItemHead(kDims == 2 ? FDSURF_TEXT("patch2") : FDSURF_TEXT("patch3"), name, index, status,
              patch.format);
  if (status == Status::kOk) {
    PutString(patch.exact ? FDSURF_TEXT(" exact") : FDSURF_TEXT(" rounded"));
    if (patch.format.acc_bits == 64) {
      DigestPatch<int64_t>(patch);
    } else if (kImageWideAccumulators) {
      DigestPatch<Int128>(patch);
    } else {
      PortExit(4);
    }
  }
  PutString(FDSURF_TEXT("\n"));
}

template <int kDims>
void Reporter::Curve(bool small, const char* name, uint16_t index, Status status,
                     const PreparedCurve<kDims>& curve) {
  if (small_only && !small) return;
  PutItemHead(kDims == 2 ? FDSURF_TEXT("curve2") : FDSURF_TEXT("curve3"), name, index, status,
              curve.format);
  if (status == Status::kOk) {
    PutString(curve.exact ? FDSURF_TEXT(" exact") : FDSURF_TEXT(" rounded"));
    if (curve.format.acc_bits == 64) {
      DigestCurve<int64_t>(curve);
    } else if (kImageWideAccumulators) {
      DigestCurve<Int128>(curve);
    } else {
      PortExit(4);
    }
  }
  PutString(FDSURF_TEXT("\n"));
}

template <int kDims>
void Reporter::Adaptive(bool small, const char* name, uint16_t index, Status status,
                        const PreparedAdaptiveCurve<kDims>& curve) {
  if (small_only && !small) return;
  PutItemHead(kDims == 2 ? FDSURF_TEXT("adaptive2") : FDSURF_TEXT("adaptive3"), name, index, status,
              curve.format);
  if (status == Status::kOk) {
    PutString(FDSURF_TEXT(" level "));
    PutUnsigned(curve.finest_level);
    DigestAdaptive(curve);
  }
  PutString(FDSURF_TEXT("\n"));
}

template <int kDims>
void Reporter::Coefficients(bool small, const char* name, uint16_t index,
                            const PowerCurve1 (&curve)[kDims]) {
  if (small_only && !small) return;
  PutString(FDSURF_TEXT("coefficients "));
  PutString(name);
  PutString(FDSURF_TEXT("-"));
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
  PutString(FDSURF_TEXT("\n"));
}

// Unused instantiations are dropped by --gc-sections on the targets.
template uint32_t StepAdaptive<2>(const PreparedAdaptiveCurve<2>&, PointDigest<2>*,
                                  PointDigest<1>*);
template uint32_t StepAdaptive<3>(const PreparedAdaptiveCurve<3>&, PointDigest<3>*,
                                  PointDigest<1>*);
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
