// SPDX-License-Identifier: MIT
// FdsurfCurve: steps a cubic Bézier curve with the fdsurf core and prints
// its points over Serial as "i x,y" (quanta), 115200 baud.
#include <fdsurf.h>

#include "bezier_curve.h"

void PrintPoint(uint16_t i, int32_t x, int32_t y) {
  Serial.print(i);
  Serial.print(' ');
  Serial.print(x);
  Serial.print(',');
  Serial.println(y);
}

void setup() {
  Serial.begin(115200);
  const int32_t x[4] = {0, 0, 3000, 3000};
  const int32_t y[4] = {0, 3000, 3000, 0};
  if (!StepBezierCurve(x, y, 16, PrintPoint)) {
    Serial.println("refused");
  }
}

void loop() {}
