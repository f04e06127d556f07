#pragma once
// Line and token reader shared by the mesh loaders: comments, line numbers, number parsing and
// the FileFormatError that names file and line, written once.
#include <stabint/errors.hpp>

#include <fstream>
#include <string>
#include <vector>

namespace stabint::io {

class TextReader {
 public:
  /// Opens `path`; a missing or unreadable file is FileFormatError(path, 0, "cannot open file").
  /// Text from `comment` to the end of a line is ignored (0: the format has no comments).
  explicit TextReader(std::string path, char comment = '#');

  const std::string& path() const { return path_; }
  /// 1-based number of the line the last token or line came from (0 before the first read).
  int line() const { return line_; }

  /// Next line that has at least one token after stripping the comment, split on whitespace.
  /// False at end of file.
  bool nextLine(std::vector<std::string>& tokens);
  /// Like nextLine, but end of file is an error naming what was expected.
  std::vector<std::string> requireLine(const std::string& expected);

  /// Next whitespace-separated token, across lines (for free-format files). False at end.
  bool nextToken(std::string& token);
  std::string requireToken(const std::string& expected);

  [[noreturn]] void fail(const std::string& message) const;
  [[noreturn]] void failAt(int line, const std::string& message) const;

  /// Parse a whole token or fail with a message naming `what` and the offending text.
  int parseInt(const std::string& token, const std::string& what) const;
  /// Also rejects nan and inf: coordinates must be finite.
  double parseReal(const std::string& token, const std::string& what) const;
  /// Count of a section or header: an integer >= 0.
  int parseCount(const std::string& token, const std::string& what) const;

 private:
  std::string path_;
  std::ifstream in_;
  char comment_;
  int line_ = 0;
  std::vector<std::string> pending_;  // tokens of the current line not yet taken by nextToken
  size_t next_pending_ = 0;
};

}  // namespace stabint::io
