#include "common/text_reader.hpp"
#include "common/validation.hpp"

#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <algorithm>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace stabint::io {

namespace {

constexpr std::size_t kChunk = 64 * 1024;

std::string mib(std::size_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

// Opens `path` for reading if it is a regular file. O_NONBLOCK: opening a FIFO for reading would
// otherwise wait for a writer forever; the type is checked on the opened descriptor (fstat), so
// what is checked is what is read.
int openRegularFile(const std::string& path, long long& size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw FileFormatError(path, 0, std::string("cannot open file: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    const bool directory = S_ISDIR(st.st_mode);
    ::close(fd);
    throw FileFormatError(path, 0,
                          directory ? "cannot open file: is a directory"
                                    : "cannot open file: not a regular file (a FIFO, device or socket)");
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  size = static_cast<long long>(st.st_size);
  return fd;
}

// read() that retries when interrupted by a signal; -1 with errno on failure.
ssize_t readSome(int fd, char* data, std::size_t bytes) {
  ssize_t got;
  do {
    got = ::read(fd, data, bytes);
  } while (got < 0 && errno == EINTR);
  return got;
}

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

}  // namespace

std::string shown(const std::string& text, std::size_t max_chars) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (out.size() >= max_chars) {
      out += "...";
      break;
    }
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      out += static_cast<char>(c);
    } else {
      static const char hex[] = "0123456789abcdef";
      out += c == '\\' ? std::string("\\\\") : std::string{'\\', 'x', hex[c >> 4], hex[c & 15]};
    }
  }
  return out;
}

std::size_t invalidUtf8At(const std::string& text, std::size_t from) {
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  for (std::size_t i = from; i < n;) {
    const unsigned char c = s[i];
    if (c < 0x80) {
      ++i;
      continue;
    }
    std::size_t length;
    unsigned char lo = 0x80, hi = 0xbf;  // allowed range of the second byte (RFC 3629, section 4)
    if (c >= 0xc2 && c <= 0xdf) {
      length = 2;
    } else if (c >= 0xe0 && c <= 0xef) {
      length = 3;
      if (c == 0xe0) lo = 0xa0;  // overlong
      if (c == 0xed) hi = 0x9f;  // surrogates
    } else if (c >= 0xf0 && c <= 0xf4) {
      length = 4;
      if (c == 0xf0) lo = 0x90;  // overlong
      if (c == 0xf4) hi = 0x8f;  // past U+10FFFF
    } else {
      return i;
    }
    if (n - i < length || s[i + 1] < lo || s[i + 1] > hi) return i;
    for (std::size_t k = 2; k < length; ++k) {
      if (s[i + k] < 0x80 || s[i + k] > 0xbf) return i;
    }
    i += length;
  }
  return std::string::npos;
}

std::string validUtf8(const std::string& text) {
  std::string out;
  for (std::size_t from = 0;;) {
    const std::size_t bad = invalidUtf8At(text, from);
    if (bad == std::string::npos) return out.append(text, from, std::string::npos);
    out.append(text, from, bad - from).append("\xef\xbf\xbd");
    from = bad + 1;
  }
}

std::string readTextFile(const std::string& path) {
  long long size = 0;
  const int fd = openRegularFile(path, size);
  std::string text;
  // The size from fstat is a hint only (a file may grow while it is read): the limit is applied
  // to what is actually read.
  text.reserve(static_cast<std::size_t>(std::min<long long>(size, kMaxTextFileBytes)) + 1);
  char chunk[kChunk];
  for (;;) {
    const ssize_t got = readSome(fd, chunk, sizeof(chunk));
    if (got < 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      throw FileFormatError(path, 0, "read failed: " + why);
    }
    if (got == 0) break;
    if (text.size() + static_cast<std::size_t>(got) > kMaxTextFileBytes) {
      ::close(fd);
      throw FileFormatError(path, 0, "file larger than " + mib(kMaxTextFileBytes) + ", the limit for a scene file");
    }
    text.append(chunk, static_cast<std::size_t>(got));
  }
  ::close(fd);
  return text;
}

TextReader::TextReader(std::string path, char comment) : path_(std::move(path)), comment_(comment) {
  fd_ = openRegularFile(path_, size_);
  buffer_.resize(kChunk);
}

TextReader::~TextReader() {
  if (fd_ >= 0) ::close(fd_);
}

bool TextReader::fill() {
  if (at_end_) return false;
  if (begin_ > 0) {  // keep the unread part at the front
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (end_ == buffer_.size()) buffer_.resize(std::min(2 * buffer_.size(), kMaxLineBytes + 1));
  const ssize_t got = readSome(fd_, buffer_.data() + end_, buffer_.size() - end_);
  if (got < 0) failAt(line_ + 1, std::string("read failed: ") + std::strerror(errno));
  if (got == 0) at_end_ = true;
  end_ += static_cast<std::size_t>(got);
  return got > 0;
}

bool TextReader::readLine(std::string& text) {
  std::size_t scanned = begin_;
  for (;;) {
    const void* nl = std::memchr(buffer_.data() + scanned, '\n', end_ - scanned);
    if (nl) {
      const std::size_t at = static_cast<std::size_t>(static_cast<const char*>(nl) - buffer_.data());
      text.assign(buffer_.data() + begin_, at - begin_);
      begin_ = at + 1;
      break;
    }
    if (end_ - begin_ > kMaxLineBytes) {
      failAt(line_ + 1, "line longer than " + mib(kMaxLineBytes) + " (is this a text file of this format?)");
    }
    scanned = end_;
    const std::size_t before = begin_;
    if (!fill()) {
      if (end_ == begin_) return false;
      text.assign(buffer_.data() + begin_, end_ - begin_);  // last line without a newline
      begin_ = end_;
      break;
    }
    scanned -= before - begin_;  // fill() moved the unread part to the front
  }
  if (line_ == INT_MAX) fail("more than " + std::to_string(INT_MAX) + " lines");
  ++line_;
  return true;
}

bool TextReader::nextLine(std::vector<std::string>& tokens) {
  tokens.clear();
  // Line-wise reading discards what the token reader had left of the current line.
  pending_.clear();
  next_pending_ = 0;
  std::string text;
  while (readLine(text)) {
    if (comment_ != 0) {
      const size_t hash = text.find(comment_);
      if (hash != std::string::npos) text.erase(hash);
    }
    for (std::size_t i = 0; i < text.size();) {
      while (i < text.size() && isSpace(text[i])) ++i;
      std::size_t j = i;
      while (j < text.size() && !isSpace(text[j])) ++j;
      if (j > i) tokens.emplace_back(text, i, j - i);
      i = j;
    }
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

void TextReader::failAt(int line, const std::string& message) const { throw FileFormatError(path_, line, message); }

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
  if (ec != std::errc() || end != last) fail("expected an integer for " + what + ", got '" + shown(token) + "'");
  return value;
}

double TextReader::parseReal(const std::string& token, const std::string& what) const {
  double value = 0.0;
  const char* last = token.data() + token.size();
  const auto [end, ec] = std::from_chars(skipPlus(token), last, value);
  if (ec != std::errc() || end != last) fail("expected a number for " + what + ", got '" + shown(token) + "'");
  if (!std::isfinite(value)) fail(what + " is not finite ('" + shown(token) + "')");
  return value;
}

double TextReader::parseCoordinate(const std::string& token, const std::string& what) const {
  const double value = parseReal(token, what);
  if (!(std::abs(value) <= validation::kMaxMagnitude)) {
    fail(what + " " + shown(token) + " exceeds " + validation::cat(validation::kMaxMagnitude) + " in magnitude");
  }
  return value;
}

int TextReader::parseCount(const std::string& token, const std::string& what) const {
  const int count = parseInt(token, what);
  if (count < 0) fail(what + " " + std::to_string(count) + " must be >= 0");
  return count;
}

std::size_t TextReader::reserveFor(int count, int min_bytes_each) const {
  return static_cast<std::size_t>(std::min<long long>(count, size_ / min_bytes_each + 1));
}

}  // namespace stabint::io
