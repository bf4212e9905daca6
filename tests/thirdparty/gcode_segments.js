#!/usr/bin/env node
// SPDX-License-Identifier: MIT
// Reads a G-code file with the npm package gcode-toolpath (cncjs's
// interpreter on top of gcode-parser) and prints the motion segments it
// produces as JSON: [{"motion": "G0"|"G1", "v1": [x,y,z], "v2": [x,y,z]}, ...].
// Positions are in millimetres: gcode-toolpath converts G20 input itself.
'use strict';

const fs = require('fs');
const path = require('path');
const Toolpath = require(path.join(__dirname, 'node_modules', 'gcode-toolpath'));

if (process.argv.length !== 3) {
  console.error('usage: gcode_segments.js FILE.gcode');
  process.exit(2);
}

const file = process.argv[2];
let text;
try {
  text = fs.readFileSync(file, 'utf8');
} catch (err) {
  console.error(`gcode_segments.js: ${file}: ${err.message}`);
  process.exit(2);
}

const segments = [];
const toolpath = new Toolpath({
  addLine: (modal, v1, v2) => {
    segments.push({ motion: modal.motion, v1: [v1.x, v1.y, v1.z], v2: [v2.x, v2.y, v2.z] });
  },
  addArcCurve: (modal) => {
    console.error(`gcode_segments.js: ${file}: unexpected arc (${modal.motion})`);
    process.exit(1);
  },
});
toolpath.loadFromStringSync(text);
process.stdout.write(JSON.stringify(segments));
