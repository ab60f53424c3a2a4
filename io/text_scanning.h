// SPDX-License-Identifier: MIT
// Text scanning shared by the mesh readers (OBJ, OFF, ASCII PLY, TetGen, MEDIT): tokens, numbers
// that refuse trailing garbage, lines counted for error messages. Internal to harap::io.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace harap::io_internal {

[[noreturn]] void Fail(std::string_view what, std::string_view problem);

std::string Lower(std::string text);
bool EndsWith(std::string_view text, std::string_view suffix);

inline bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

/// Splits off the next whitespace-separated token of `line` (which is advanced past it).
std::string_view NextToken(std::string_view& line);

/// Parses a whole token as a double; false if it is not a number. Non-finite spellings ("nan",
/// "inf") and overflow parse, so the caller can say that the number is non-finite rather than
/// malformed.
bool ParseDouble(std::string_view token, double& value);

/// Parses a whole token as an integer; false on garbage or overflow.
bool ParseInteger(std::string_view token, int64_t& value);

/// `line` without a `#` comment.
std::string_view StripComment(std::string_view line);

/// The token in single quotes for messages: at most 40 characters, non-printable ones as '?'.
std::string Quote(std::string_view token);

/// Iterates over the lines of a text buffer, counting them (1-based). A line ends at "\n",
/// "\r\n" or a lone "\r".
class LineReader {
 public:
  explicit LineReader(std::string_view data) : data_(data) {}

  bool Next(std::string_view& line);
  /// The next line with content, `#` comments stripped and blank lines skipped; false at the end.
  bool NextContent(std::string_view& line);
  size_t line_number() const { return line_number_; }
  /// Offset of the first byte after the last line returned (and its line ending).
  size_t position() const { return position_ < data_.size() ? position_ : data_.size(); }

 private:
  std::string_view data_;
  size_t position_ = 0;
  size_t line_number_ = 0;
};

/// Sequential whitespace-separated tokens across lines, with line numbers; optionally skipping
/// `#` comments (to the end of the line).
class TokenCursor {
 public:
  TokenCursor(std::string_view data, size_t first_line, bool skip_comments)
      : data_(data), line_(first_line), skip_comments_(skip_comments) {}

  /// The next token, or an empty view at the end of the data.
  std::string_view Next();
  /// The line of the last token returned (or of the end of the data).
  size_t line() const { return line_; }

 private:
  std::string_view data_;
  size_t position_ = 0;
  size_t line_;
  bool skip_comments_;
};

}  // namespace harap::io_internal
