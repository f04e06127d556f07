#include "io/text_reader.hpp"

#include <charconv>
#include <cmath>
#include <sstream>

namespace stabint::io {

TextReader::TextReader(std::string path, char comment) : path_(std::move(path)), in_(path_), comment_(comment) {
  if (!in_) throw FileFormatError(path_, 0, "cannot open file");
}

bool TextReader::nextLine(std::vector<std::string>& tokens) {
  tokens.clear();
  // Line-wise reading discards what the token reader had left of the current line.
  pending_.clear();
  next_pending_ = 0;
  std::string text;
  while (std::getline(in_, text)) {
    ++line_;
    if (comment_ != 0) {
      const size_t hash = text.find(comment_);
      if (hash != std::string::npos) text.erase(hash);
    }
    std::istringstream words(text);
    for (std::string w; words >> w;) tokens.push_back(std::move(w));
    if (!tokens.empty()) return true;
  }
  return false;
}

std::vector<std::string> TextReader::requireLine(const std::string& expected) {
  std::vector<std::string> tokens;
  if (!nextLine(tokens)) fail("unexpected end of file, expected " + expected);
  return tokens;
}

bool TextReader::nextToken(std::string& token) {
  if (next_pending_ >= pending_.size()) {
    std::vector<std::string> tokens;
    if (!nextLine(tokens)) return false;
    pending_ = std::move(tokens);
    next_pending_ = 0;
  }
  token = pending_[next_pending_++];
  return true;
}

std::string TextReader::requireToken(const std::string& expected) {
  std::string token;
  if (!nextToken(token)) fail("unexpected end of file, expected " + expected);
  return token;
}

void TextReader::fail(const std::string& message) const { failAt(line_, message); }

void TextReader::failAt(int line, const std::string& message) const {
  throw FileFormatError(path_, line, message);
}

namespace {

// from_chars is locale-independent (strtod would read "1,5" in a German locale) but rejects a
// leading '+', which mesh writers do emit.
const char* skipPlus(const std::string& token) {
  const char* first = token.data();
  if (token.size() > 1 && first[0] == '+' && first[1] != '-') ++first;
  return first;
}

}  // namespace

int TextReader::parseInt(const std::string& token, const std::string& what) const {
  int value = 0;
  const char* last = token.data() + token.size();
  const auto [end, ec] = std::from_chars(skipPlus(token), last, value);
  if (ec != std::errc() || end != last) fail("expected an integer for " + what + ", got '" + token + "'");
  return value;
}

double TextReader::parseReal(const std::string& token, const std::string& what) const {
  double value = 0.0;
  const char* last = token.data() + token.size();
  const auto [end, ec] = std::from_chars(skipPlus(token), last, value);
  if (ec != std::errc() || end != last) fail("expected a number for " + what + ", got '" + token + "'");
  if (!std::isfinite(value)) fail(what + " is not finite ('" + token + "')");
  return value;
}

int TextReader::parseCount(const std::string& token, const std::string& what) const {
  const int count = parseInt(token, what);
  if (count < 0) fail(what + " " + std::to_string(count) + " must be >= 0");
  return count;
}

}  // namespace stabint::io
