// SPDX-License-Identifier: MIT
// The G-code reader's first half: a program's text as lines of words
// (letter + number), without comments, line numbers and checksums. The
// interpreter (gcode_io.cc) gives the words their meaning.
#pragma once

#include <string>
#include <vector>

namespace fdsurf::host::gcode {

/// One word: an upper-case letter and its number, as written (for messages).
struct Word {
  char letter = 0;
  double value = 0;
  std::string text;  // e.g. "X-2.5"
};

struct Line {
  int number = 0;  // line of the file, from 1
  std::vector<Word> words;
  bool block_delete = false;  // the line started with '/'
};

/// The program's lines with words, in order. A line holding only `%` starts
/// the program (when it is the first) or ends it (the rest of the file is
/// not read); blank and comment-only lines are left out. Marlin checksums
/// (`*71` after the words: the XOR of the line's bytes before '*') are
/// checked and removed; `N` line numbers are removed. Throws InputError
/// ("NAME:LINE: ...") for a word without a number, an unclosed comment, an
/// expression or parameter (`#`, `[`), or a wrong checksum.
std::vector<Line> SplitLines(const std::string& text, const std::string& name);

}  // namespace fdsurf::host::gcode
