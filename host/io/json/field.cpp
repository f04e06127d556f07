// Reading JSON with its path: the Field every reader checks values with, whose errors name the
// file and the field ("springs[3].stiffness"), and the checks a JSON text passes before it is read.
#include "io/json/json_internal.hpp"

#include "common/text_reader.hpp"
#include "common/validation.hpp"

#include <stabint/errors.hpp>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstddef>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace stabint::io {

void Field::fail(const std::string& message) const {
  throw FileFormatError(*file_, 0, (path_.empty() ? std::string("top level") : path_) + ": " + message);
}

void Field::requireObject() const {
  if (!value_->is_object()) fail(std::string("expected an object, got ") + value_->type_name());
}
void Field::requireArray() const {
  if (!value_->is_array()) fail(std::string("expected an array, got ") + value_->type_name());
}

std::optional<Field> Field::find(const std::string& key) const {
  requireObject();
  const auto it = value_->find(key);
  if (it == value_->end()) return std::nullopt;
  return Field(*it, path_.empty() ? key : path_ + "." + key, *file_);
}
Field Field::member(const std::string& key) const {
  auto f = find(key);
  if (!f) fail("missing field '" + key + "'");
  return *f;
}

size_t Field::size() const {
  requireArray();
  return value_->size();
}
Field Field::operator[](size_t i) const {
  requireArray();
  return Field((*value_)[i], path_ + "[" + std::to_string(i) + "]", *file_);
}

void Field::allowOnly(const std::set<std::string>& keys) const {
  requireObject();
  for (const auto& item : value_->items()) {
    if (item.key().empty() || item.key()[0] == '_') continue;
    if (!keys.count(item.key())) {
      std::string expected;
      for (const auto& k : keys) expected += (expected.empty() ? "" : ", ") + k;
      fail("unknown field '" + shown(item.key()) + "' (expected one of: " + expected + ")");
    }
  }
}

double Field::number() const {
  if (!value_->is_number()) fail(std::string("expected a number, got ") + value_->type_name());
  const double x = value_->get<double>();
  if (!std::isfinite(x)) fail("expected a finite number");
  return x;
}
double Field::eventValue() const {
  const double x = number();
  if (!(std::abs(x) <= validation::kMaxMagnitude)) fail(text(x) + " exceeds 1e150 in magnitude");
  return x;
}
Eigen::Vector3d Field::eventVector() const {
  if (!value_->is_array() || value_->size() != 3) fail("expected an array of 3 numbers [x, y, z], got " + shortDump());
  return Eigen::Vector3d((*this)[0].eventValue(), (*this)[1].eventValue(), (*this)[2].eventValue());
}
double Field::nonNegative() const {
  const double x = number();
  if (x < 0.0) fail("must be >= 0, got " + text(x));
  return x;
}
double Field::positive() const {
  const double x = number();
  if (!(x > 0.0)) fail("must be > 0, got " + text(x));
  return x;
}
int Field::integer() const {
  if (value_->is_number_float()) {
    const double x = value_->get<double>();
    if (std::isfinite(x) && x == std::floor(x) && std::abs(x) <= INT_MAX) return static_cast<int>(x);
    fail("expected an integer, got " + value_->dump());
  }
  if (!value_->is_number()) fail(std::string("expected an integer, got ") + value_->type_name());
  if (value_->is_number_unsigned()) {
    if (value_->get<unsigned long long>() > static_cast<unsigned long long>(INT_MAX)) fail("integer out of range");
    return static_cast<int>(value_->get<unsigned long long>());
  }
  const long long v = value_->get<long long>();
  if (v < INT_MIN || v > INT_MAX) fail("integer out of range");
  return static_cast<int>(v);
}
int Field::particle(int n) const {
  const int i = integer();
  if (i < 0 || i >= n) fail("particle index " + std::to_string(i) + " out of range [0, " + std::to_string(n) + ")");
  return i;
}
std::string Field::string() const {
  if (!value_->is_string()) fail(std::string("expected a string, got ") + value_->type_name());
  return value_->get<std::string>();
}
Eigen::Vector3d Field::vector3() const {
  if (!value_->is_array() || value_->size() != 3) fail("expected an array of 3 numbers [x, y, z], got " + shortDump());
  return Eigen::Vector3d((*this)[0].number(), (*this)[1].number(), (*this)[2].number());
}
std::vector<int> Field::particles(int n) const {
  std::vector<int> out(size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = (*this)[i].particle(n);
  return out;
}

std::string Field::text(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// At most 40 characters of the value, escaped. Only as much of the value is walked as is
// shown: dump() of the whole value recursed to its bottom (70,000 levels overflowed the stack)
// and copied a million entries to show forty characters.
std::string Field::shortDump() const {
  std::string d;
  brief(*value_, d);
  return shown(d.size() > 40 ? d.substr(0, 37) + "..." : d);
}
void Field::brief(const json& v, std::string& out) {
  if (!v.is_structured()) {
    out += v.dump();
    return;
  }
  out += v.is_array() ? '[' : '{';
  for (auto it = v.begin(); it != v.end() && out.size() <= 40; ++it) {
    if (it != v.begin()) out += ',';
    if (v.is_object()) out += json(it.key()).dump() + ':';
    brief(*it, out);  // each level adds a character: at most about 40 deep
  }
  out += v.is_array() ? ']' : '}';
}

namespace {

// Deepest nesting of arrays and objects a scene file may have (a scene needs 4 levels). The
// parser copes with any depth, but code that walks a value recursively does not: 70,000 levels
// overflowed the stack. Scanned before parsing, so that the error has a line.
constexpr int kMaxJsonDepth = 64;

void checkNesting(const std::string& text, const std::string& file) {
  int depth = 0, line = 1;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (in_string) {
      if (c == '\\' && i + 1 < text.size() && text[i + 1] != '\n')
        ++i;  // an escaped quote ends nothing
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) {
        throw FileFormatError(file, line, "JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
      }
    } else if (c == ']' || c == '}') {
      --depth;  // unbalanced brackets are the parser's to report
    }
  }
}

// A key given twice in one object: the JSON library keeps the last one silently, so a scene
// would run with a value the reader of the file may not have seen, although every key is
// promised to be checked. Scanned after a successful parse, when the text is known to be valid
// JSON: a string right after '{' or after ',' in an object is a key. Keys are compared decoded
// ("a" and "\u0061" are the same key).
void checkDuplicateKeys(const std::string& text, const std::string& file) {
  struct Container {
    bool object;
    std::map<std::string, int> keys;  // key -> line of its first occurrence
  };
  std::vector<Container> open;
  bool expect_key = false;
  int line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '{' || c == '[') {
      open.push_back({c == '{', {}});
      expect_key = c == '{';
    } else if (c == '}' || c == ']') {
      if (!open.empty()) open.pop_back();  // valid JSON is balanced; never trust it past that
      expect_key = false;
    } else if (c == ',') {
      expect_key = !open.empty() && open.back().object;
    } else if (c == '"') {
      const std::size_t start = i;
      bool escaped = false;
      for (++i; i < text.size() && text[i] != '"'; ++i) {
        if (text[i] == '\\') escaped = true, ++i;  // valid JSON: the escape is complete
      }
      if (i >= text.size()) return;  // an unterminated string: the parser's to report
      if (!expect_key || open.empty()) continue;
      expect_key = false;
      std::string key = text.substr(start + 1, i - start - 1);
      if (escaped) key = json::parse(text.substr(start, i - start + 1)).get<std::string>();
      const auto [first, inserted] = open.back().keys.emplace(key, line);
      if (!inserted) {
        throw FileFormatError(file, line,
                              "duplicate key '" + shown(key) + "' (first on line " + std::to_string(first->second) +
                                  "): one of them would be ignored");
      }
    }
  }
}

// The JSON library ends its input at a NUL byte and reports success, so whatever follows one
// would be ignored (and the key scan below would read it as JSON): a NUL is refused.
void checkNoNul(const std::string& text, const std::string& file) {
  const std::size_t at = text.find('\0');
  if (at == std::string::npos) return;
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
  throw FileFormatError(file, line, "NUL byte at offset " + std::to_string(at) + ": not a JSON text");
}

// The offset of the first occurrence of the number `token` outside strings and not inside a
// longer number or word.
std::optional<size_t> findNumberToken(const std::string& text, const std::string& token) {
  const auto part = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '.'; };
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (text.compare(i, token.size(), token) == 0 && (i == 0 || !part(text[i - 1])) &&
               (i + token.size() >= text.size() || !part(text[i + token.size()]))) {
      return i;
    }
  }
  return std::nullopt;
}

// Malformed JSON at byte `offset` of `text`: its line and column, and what the parser said.
[[noreturn]] void throwMalformedAt(const std::string& text, const std::string& file, size_t offset,
                                   const std::string& what) {
  int line = 1;
  size_t line_start = 0;
  for (size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  throw FileFormatError(file, line,
                        "malformed JSON (column " + std::to_string(offset - line_start + 1) + "): " + shown(what, 400));
}

}  // namespace

json parseJson(const std::string& text, const std::string& file) {
  checkNoNul(text, file);
  checkNesting(text, file);
  try {
    json doc = json::parse(text);
    checkDuplicateKeys(text, file);
    return doc;
  } catch (const json::parse_error& e) {
    // e.byte is the 1-based offset of the offending character; report line and column.
    std::string what = e.what();
    const size_t column_at = what.find("column");
    const size_t colon = column_at == std::string::npos ? std::string::npos : what.find(": ", column_at);
    if (colon != std::string::npos) what = what.substr(colon + 2);
    // The message quotes what was last read, raw bytes included.
    throwMalformedAt(text, file, std::min<size_t>(e.byte == 0 ? 0 : e.byte - 1, text.size()), what);
  } catch (const json::exception& e) {
    // Number overflow ("1e999") comes without a position: the number it quotes is found in the
    // text, outside strings, to give its line.
    std::string what = e.what();
    const size_t bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    const size_t open = what.find('\'');
    const size_t close = open == std::string::npos ? std::string::npos : what.find('\'', open + 1);
    if (close != std::string::npos && close > open + 1) {
      if (const auto at = findNumberToken(text, what.substr(open + 1, close - open - 1)))
        throwMalformedAt(text, file, *at, what);
    }
    throw FileFormatError(file, 0, "malformed JSON: " + shown(what, 400));
  }
}

}  // namespace stabint::io
