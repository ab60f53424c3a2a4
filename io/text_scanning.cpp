// SPDX-License-Identifier: MIT
#include "io/text_scanning.h"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cstdlib>
#include <system_error>

#include "framework/error.h"

namespace harap::io_internal {

void Fail(std::string_view what, std::string_view problem) {
  throw InputError(fmt::format("{}: {}", what, problem));
}

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

bool EndsWith(std::string_view text, std::string_view suffix) {
  return text.size() >= suffix.size() && text.substr(text.size() - suffix.size()) == suffix;
}

std::string_view NextToken(std::string_view& line) {
  size_t start = 0;
  while (start < line.size() && IsSpace(line[start])) ++start;
  size_t end = start;
  while (end < line.size() && !IsSpace(line[end])) ++end;
  std::string_view token = line.substr(start, end - start);
  line.remove_prefix(end);
  return token;
}

bool ParseDouble(std::string_view token, double& value) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (end != token.data() + token.size()) return false;
  if (error == std::errc::result_out_of_range) {
    // from_chars reports both overflow and underflow; strtod tells them apart (denormals and
    // zero are fine, overflow becomes inf and is reported as non-finite by the caller).
    value = std::strtod(std::string(token).c_str(), nullptr);
    return true;
  }
  return error == std::errc();
}

bool ParseInteger(std::string_view token, int64_t& value) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

std::string_view StripComment(std::string_view line) {
  const size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

std::string Quote(std::string_view token) {
  constexpr size_t kMax = 40;
  std::string text(token.substr(0, kMax));
  for (char& c : text) {
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  }
  return fmt::format("'{}{}'", text, token.size() > kMax ? "..." : "");
}

bool LineReader::Next(std::string_view& line) {
  if (position_ >= data_.size()) return false;
  // A line ends at "\n", "\r\n" or a lone "\r" (classic Mac OS), so files with mixed line
  // endings keep every line separate and the numbers in messages match what an editor shows.
  const size_t end = data_.find_first_of("\r\n", position_);
  const size_t stop = end == std::string_view::npos ? data_.size() : end;
  line = data_.substr(position_, stop - position_);
  position_ = stop + 1;
  if (stop < data_.size() && data_[stop] == '\r' && position_ < data_.size() &&
      data_[position_] == '\n') {
    ++position_;
  }
  ++line_number_;
  return true;
}

bool LineReader::NextContent(std::string_view& line) {
  while (Next(line)) {
    line = StripComment(line);
    std::string_view probe = line;
    if (!NextToken(probe).empty()) return true;
  }
  return false;
}

std::string_view TokenCursor::Next() {
  while (position_ < data_.size()) {
    const char c = data_[position_];
    if (c == '\n') {
      ++line_;
      ++position_;
    } else if (IsSpace(c)) {
      ++position_;
    } else if (skip_comments_ && c == '#') {
      while (position_ < data_.size() && data_[position_] != '\n') ++position_;
    } else {
      break;
    }
  }
  const size_t start = position_;
  while (position_ < data_.size() && !IsSpace(data_[position_]) && data_[position_] != '\n' &&
         !(skip_comments_ && data_[position_] == '#')) {
    ++position_;
  }
  return data_.substr(start, position_ - start);
}

}  // namespace harap::io_internal
