// SPDX-License-Identifier: MIT
#include "gcode_lines.h"

#include <cctype>
#include <string_view>

#include "fdsurf/host/errors.h"

namespace fdsurf::host::gcode {
namespace {

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

// Reads one line's words; `error` builds the message for its line.
class LineScanner {
 public:
  LineScanner(std::string_view text, std::string where) : text_(text), where_(std::move(where)) {}

  [[nodiscard]] InputError Error(const std::string& what) const {
    return InputError(where_ + ": " + what);
  }

  // Where the checksum star is (outside comments), or npos.
  [[nodiscard]] std::size_t FindStar() const {
    bool in_paren = false;
    for (std::size_t i = 0; i < text_.size(); ++i) {
      const char c = text_[i];
      if (in_paren) {
        in_paren = c != ')';
      } else if (c == '(') {
        in_paren = true;
      } else if (c == ';') {
        return std::string_view::npos;
      } else if (c == '*') {
        return i;
      }
    }
    return std::string_view::npos;
  }

  // Checks a Marlin checksum `*N` at `star` and returns the text before it.
  [[nodiscard]] std::string_view CheckChecksum(std::size_t star) const {
    unsigned sum = 0;
    for (std::size_t i = 0; i < star; ++i) sum ^= static_cast<unsigned char>(text_[i]);
    std::size_t i = star + 1;
    unsigned given = 0;
    const std::size_t digits_at = i;
    while (i < text_.size() && IsDigit(text_[i]) && i - digits_at < 4) {
      given = given * 10 + static_cast<unsigned>(text_[i] - '0');
      ++i;
    }
    if (i == digits_at) throw Error("checksum '*': not a number");
    const std::string_view rest = text_.substr(i);
    const std::size_t tail = rest.find_first_not_of(" \t\f\v");
    if (tail != std::string_view::npos && rest[tail] != ';' && rest[tail] != '(') {
      throw Error("unexpected text after the checksum: '" + std::string(rest.substr(tail)) + "'");
    }
    if (given != sum) {
      throw Error("checksum *" + std::to_string(given) + " is wrong: the line's bytes before '*' " +
                  "give " + std::to_string(sum));
    }
    return text_.substr(0, star);
  }

  // The words of `body` (the line without its checksum).
  void Scan(std::string_view body, Line* line, bool* percent) {
    std::size_t i = 0;
    const auto skip_blanks = [&] {
      while (i < body.size() && IsBlank(body[i])) ++i;
    };
    skip_blanks();
    if (i < body.size() && body[i] == '/') {
      line->block_delete = true;
      ++i;
    }
    while (true) {
      skip_blanks();
      if (i >= body.size() || body[i] == ';') return;
      const char c = body[i];
      if (c == '(') {
        const std::size_t close = body.find(')', i);
        if (close == std::string_view::npos) throw Error("comment '(' is not closed on its line");
        i = close + 1;
      } else if (c == '%') {
        *percent = true;
        ++i;
      } else if (c == '#' || c == '[') {
        throw Error(std::string("'") + c + "': parameters and expressions are not supported");
      } else if (c == 'O' || c == 'o') {
        throw Error("O-word subroutines are not supported");
      } else if (std::isalpha(static_cast<unsigned char>(c)) != 0) {
        Word word = ReadWord(body, &i);
        if (word.letter != 'N') line->words.push_back(std::move(word));
      } else {
        throw Error(std::string("unexpected character '") + c + "'");
      }
    }
  }

 private:
  // A letter, optional blanks, and a number: [+-] digits [. digits] or
  // [+-] . digits (G-code has no exponents: "X1E3" is X1 then E3).
  Word ReadWord(std::string_view body, std::size_t* at) {
    std::size_t i = *at;
    Word word;
    word.letter = static_cast<char>(std::toupper(static_cast<unsigned char>(body[i])));
    ++i;
    while (i < body.size() && IsBlank(body[i])) ++i;
    const std::size_t start = i;
    std::string number;
    if (i < body.size() && (body[i] == '+' || body[i] == '-')) number += body[i++];
    std::size_t digits = 0;
    while (i < body.size() && IsDigit(body[i])) {
      number += body[i++];
      ++digits;
    }
    if (i < body.size() && body[i] == '.') {
      number += body[i++];
      while (i < body.size() && IsDigit(body[i])) {
        number += body[i++];
        ++digits;
      }
    }
    if (digits == 0 || digits > 30) {
      std::size_t end = start;
      while (end < body.size() && !IsBlank(body[end]) && end - start < 12) ++end;
      const std::string shown(body.substr(start, end - start));
      throw Error(std::string("word '") + word.letter + "': " +
                  (shown.empty() ? std::string("no number") : "'" + shown + "' is not a number"));
    }
    word.value = std::stod(number);
    word.text = std::string(1, word.letter) + number;
    *at = i;
    return word;
  }

  std::string_view text_;
  std::string where_;
};

}  // namespace

std::vector<Line> SplitLines(const std::string& text, const std::string& name) {
  std::vector<Line> lines;
  bool started_by_percent = false;
  bool any_words = false;
  std::size_t pos = 0;
  int number = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view raw(text.data() + pos, end - pos);
    pos = end + 1;
    ++number;
    if (!raw.empty() && raw.back() == '\r') raw.remove_suffix(1);
    LineScanner scanner(raw, name + ":" + std::to_string(number));
    const std::size_t star = scanner.FindStar();
    const std::string_view body =
        star == std::string_view::npos ? raw : scanner.CheckChecksum(star);
    Line line;
    line.number = number;
    bool percent = false;
    scanner.Scan(body, &line, &percent);
    if (percent) {
      if (!line.words.empty()) throw scanner.Error("'%' must be on a line of its own");
      // The first '%' opens the program; one after words (or a second) ends it.
      if (any_words || started_by_percent) break;
      started_by_percent = true;
      continue;
    }
    if (line.words.empty()) continue;
    any_words = true;
    lines.push_back(std::move(line));
  }
  return lines;
}

}  // namespace fdsurf::host::gcode
