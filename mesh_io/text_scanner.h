// Reading text mesh formats: a line at a time, words separated by blanks, numbers parsed to the
// nearest double (std::from_chars: correctly rounded, locale-free).
#pragma once

#include "kernel/core/status.h"

#include <charconv>
#include <cstdlib>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

namespace gk::mesh_io {

class TextScanner {
 public:
  explicit TextScanner(std::string_view text) : text_(text) {}

  // The next line (without its end: LF, CRLF or a lone CR), false at the end of the text. Counts
  // lines from 1.
  bool next_line(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const std::size_t end = text_.find_first_of("\r\n", pos_);
    line = text_.substr(pos_, end == std::string_view::npos ? std::string_view::npos : end - pos_);
    if (end == std::string_view::npos) pos_ = text_.size();
    else pos_ = end + ((text_[end] == '\r' && end + 1 < text_.size() && text_[end + 1] == '\n') ? 2 : 1);
    ++line_number_;
    return true;
  }
  std::size_t line_number() const { return line_number_; }
  std::size_t offset() const { return pos_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_number_ = 0;
};

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// The next blank-separated word of `line`, consumed; empty when there is none.
inline std::string_view next_word(std::string_view& line) {
  std::size_t start = 0;
  while (start < line.size() && is_blank(line[start])) ++start;
  std::size_t end = start;
  while (end < line.size() && !is_blank(line[end])) ++end;
  const std::string_view word = line.substr(start, end - start);
  line.remove_prefix(end);
  return word;
}

// A finite double written as text (a leading '+' allowed); false for anything else.
inline bool parse_double(std::string_view word, double& out) {
  if (!word.empty() && word.front() == '+') {
    word.remove_prefix(1);
    if (!word.empty() && (word.front() == '-' || word.front() == '+')) return false;  // "+-5" is no number
  }
  if (word.empty()) return false;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), out);
  if (end != word.data() + word.size()) return false;
  if (ec == std::errc::result_out_of_range) {
    // Too small for a double (1e-400) rounds to a subnormal or zero, as strtod rounds it (this
    // process never sets a locale, so strtod reads '.' as the point); too large is refused.
    const std::string copy(word);
    out = std::strtod(copy.c_str(), nullptr);
    return std::isfinite(out) && std::fabs(out) < 1.0;
  }
  return ec == std::errc() && std::isfinite(out);
}

inline bool parse_integer(std::string_view word, long long& out) {
  if (!word.empty() && word.front() == '+') {
    word.remove_prefix(1);
    if (!word.empty() && (word.front() == '-' || word.front() == '+')) return false;
  }
  if (word.empty()) return false;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), out);
  return ec == std::errc() && end == word.data() + word.size();
}

// True when nothing but blanks is left of the line.
inline bool at_end(std::string_view line) { return next_word(line).empty(); }

inline Error line_error(std::size_t line, const std::string& message) {
  return invalid_argument("line " + std::to_string(line), message);
}

}  // namespace gk::mesh_io
