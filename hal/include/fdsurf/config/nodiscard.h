// SPDX-License-Identifier: MIT
// FDSURF_NODISCARD: marks a result type (Status, IoStatus, DecodeResult) so
// that a call whose result is dropped is a warning (an error under -Werror).
//
// It lives here, beside the HAL interfaces, because fdsurf_hal is the lowest
// layer: the core links it and includes its headers, so both hal::IoStatus and
// the core's Status/DecodeResult can use one macro without the HAL depending on
// the engine. It is not HAL-specific; it is in fdsurf/config/, not fdsurf/hal/.
//
// The compilers it has to please, all in C++14 mode for the core:
//   - avr-g++ 5.4 knows no nodiscard (__has_cpp_attribute(nodiscard) is 0)
//     and warns "attribute directive ignored" for [[nodiscard]]; its
//     warn_unused_result applies to functions only, not types. So: nothing.
//   - GCC 7 and later accept [[nodiscard]] on a type in C++14 mode without a
//     -Wpedantic warning.
//   - Clang (clang-tidy) warns that [[nodiscard]] before C++17 is an
//     extension (-Wc++17-attribute-extensions, part of -Wpedantic); its own
//     [[clang::warn_unused_result]] means the same and does not.
// An explicit (void) cast silences it; each one should say why it is safe.
#pragma once

#if defined(__has_cpp_attribute)
#if __cplusplus >= 201703L && __has_cpp_attribute(nodiscard)
#define FDSURF_NODISCARD [[nodiscard]]
#elif defined(__clang__)
#if __has_cpp_attribute(clang::warn_unused_result)
#define FDSURF_NODISCARD [[clang::warn_unused_result]]
#endif
#elif defined(__GNUC__)
#if __has_cpp_attribute(nodiscard)
#define FDSURF_NODISCARD [[nodiscard]]
#endif
#endif
#endif

#ifndef FDSURF_NODISCARD
#define FDSURF_NODISCARD
#endif
