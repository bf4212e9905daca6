#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The Arduino library as the Arduino IDE (AVR core 1.8, avr-gcc 5.4) builds
# it for a Mega 2560: scripts/arduino_library.sh assembles it, every library
# source and the FdsurfCurve example (its .ino with `#include <Arduino.h>`
# prepended, as arduino-builder does, and its .cpp) are compiled with the
# IDE's flags, unchanged (-std=gnu++11), against a test-only Arduino.h shim
# (tests/package/arduino_shim/) and linked as the IDE links. With SIMAVR
# (targets' fdsurf_simavr), the ELF runs and its Serial output is checked:
# 17 points, each within 0.51 quanta of the exact curve.
# Usage: arduino_sketch.sh SOURCE_DIR WORK_DIR [SIMAVR]
set -euo pipefail
src=$(cd "$1" && pwd)
work=$2
simavr=${3:-}
rm -rf "$work"
mkdir -p "$work/obj" "$work/sketch"
work=$(cd "$work" && pwd)
shim=$src/tests/package/arduino_shim
lib=$("$src/scripts/arduino_library.sh" "$work/library")
sketch_src=$lib/examples/FdsurfCurve

# platform.txt of the Arduino AVR core 1.8.x (compiler.cpp.flags, build.*).
cxxflags=(-c -g -Os -w -std=gnu++11 -fpermissive -fno-exceptions -ffunction-sections
  -fdata-sections -fno-threadsafe-statics -Wno-error=narrowing -flto -mmcu=atmega2560
  -DF_CPU=16000000L -DARDUINO=10819 -DARDUINO_AVR_MEGA2560 -DARDUINO_ARCH_AVR)
includes=(-I"$shim" -I"$lib/src")
objects=()
compile() { # SOURCE OBJECT [EXTRA FLAGS...]
  local source=$1 object=$2
  shift 2
  avr-g++ "${cxxflags[@]}" "$@" "${includes[@]}" "$source" -o "$object"
  objects+=("$object")
}

# The library: every .cpp under src/, recursively.
n=0
while IFS= read -r f; do
  n=$((n + 1))
  compile "$f" "$work/obj/lib$n.o"
done < <(find "$lib/src" -name '*.cpp' | sort)

# The sketch, copied and preprocessed as arduino-builder does.
cp "$sketch_src"/* "$work/sketch/"
{
  echo '#include <Arduino.h>'
  echo "#line 1 \"$sketch_src/FdsurfCurve.ino\""
  cat "$sketch_src/FdsurfCurve.ino"
} >"$work/sketch/FdsurfCurve.ino.cpp"
compile "$work/sketch/FdsurfCurve.ino.cpp" "$work/obj/sketch.o"
compile "$work/sketch/bezier_curve.cpp" "$work/obj/bezier_curve.o"
compile "$shim/arduino_main.cpp" "$work/obj/shim_main.o"

elf=$work/FdsurfCurve.ino.elf
avr-gcc -w -Os -g -flto -fuse-linker-plugin -Wl,--gc-sections -mmcu=atmega2560 -o "$elf" \
  "${objects[@]}" -lm
avr-size "$elf"
echo "library: $n sources compiled with the Arduino IDE's flags; sketch linked"

if [ -n "$simavr" ]; then
  timeout 60 "$simavr" -m atmega2560 -f 16000000 "$elf" >"$work/serial.txt"
  python3 - "$work/serial.txt" <<'PY'
import sys
from fractions import Fraction as F
lines = open(sys.argv[1], newline="").read().split("\r\n")
assert lines[-1] == "", "output does not end with a line"
lines = lines[:-1]
assert len(lines) == 17, f"{len(lines)} points, expected 17: {lines}"
worst = 0
for i, line in enumerate(lines):
    index, point = line.split(" ")
    x, y = (int(v) for v in point.split(","))
    assert int(index) == i, line
    u = F(i, 16)
    exact = (3000 * (3 * (1 - u) * u * u + u ** 3), 3000 * 3 * u * (1 - u))
    worst = max(worst, abs(x - exact[0]), abs(y - exact[1]))
assert worst <= F(51, 100), f"a point is {float(worst)} quanta off"
print(f"serial: 17 points, worst {float(worst):.3f} quanta from the exact curve")
PY
fi
