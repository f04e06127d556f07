#pragma once
// Line and token reader shared by the mesh loaders: comments, line numbers, number parsing and
// the FileFormatError that names file and line, written once. Every text file the library reads
// goes through here (or through readTextFile), so the limits below hold for all of them: only
// regular files are opened (a FIFO would block forever, /dev/zero never ends, a directory is no
// file), a line may not exceed kMaxLineBytes, and room for the records a header announces is
// reserved only as far as the file has bytes for them, so no input makes the library wait or
// allocate without bound.
#include <stabint/errors.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace stabint::io {

/// Longest line the mesh loaders accept (an OBJ face of 200,000 corners takes about 1.3 MiB).
constexpr std::size_t kMaxLineBytes = std::size_t(4) << 20;
/// Largest file readTextFile reads whole (JSON scene files).
constexpr std::size_t kMaxTextFileBytes = std::size_t(256) << 20;

/// `text` as it may appear in an error message: printable ASCII kept, every other byte written
/// as \xNN, and at most `max_chars` characters of it (then "..."). File bytes are never echoed
/// raw.
std::string shown(const std::string& text, std::size_t max_chars = 64);

/// Offset of the first byte of `text`, from `from` on, that does not belong to well-formed UTF-8
/// (no overlong forms, surrogates or code points past U+10FFFF), or std::string::npos.
std::size_t invalidUtf8At(const std::string& text, std::size_t from = 0);

/// `text` with every byte that does not belong to well-formed UTF-8 replaced by U+FFFD.
std::string validUtf8(const std::string& text);

/// The whole content of the regular file `path`, at most kMaxTextFileBytes. FileFormatError(path,
/// 0, ...) when it cannot be opened, is not a regular file or is larger.
std::string readTextFile(const std::string& path);

class TextReader {
 public:
  /// Opens `path`; a missing or unreadable file, or one that is not a regular file (directory,
  /// FIFO, device), is FileFormatError(path, 0, "cannot open file: <why>").
  /// Text from `comment` to the end of a line is ignored (0: the format has no comments).
  explicit TextReader(std::string path, char comment = '#');
  ~TextReader();
  TextReader(const TextReader&) = delete;
  TextReader& operator=(const TextReader&) = delete;

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
  /// parseReal, and at most validation::kMaxMagnitude in magnitude, as validateScene requires of
  /// positions: the file's line is known here and not there.
  double parseCoordinate(const std::string& token, const std::string& what) const;
  /// Count of a section or header: an integer >= 0.
  int parseCount(const std::string& token, const std::string& what) const;
  /// How many of `count` announced records, each at least `min_bytes_each` bytes of the file,
  /// to reserve room for: no more than the file has bytes for. A header is untrusted (a count of
  /// 2e9 in a 1 kB file must not allocate gigabytes); reading then fails at the end of the file
  /// naming the record that is missing.
  std::size_t reserveFor(int count, int min_bytes_each) const;

 private:
  /// Next raw line without its newline; false at end of file.
  bool readLine(std::string& text);
  bool fill();

  std::string path_;
  int fd_ = -1;
  long long size_ = 0;  // of the file when opened
  char comment_;
  int line_ = 0;
  std::vector<char> buffer_;
  std::size_t begin_ = 0, end_ = 0;  // unread part of buffer_
  bool at_end_ = false;
  std::vector<std::string> pending_;  // tokens of the current line not yet taken by nextToken
  std::size_t next_pending_ = 0;
};

}  // namespace stabint::io
