#pragma once
// A minimal CSV writer: a header line, then rows of numbers and plain words (no quoting needed:
// the study writes no commas inside fields).
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace study {

class CsvWriter {
 public:
  /// Opens `path` for writing (throws std::runtime_error naming it when it cannot) and writes
  /// the header.
  CsvWriter(const std::string& path, const std::vector<std::string>& columns);

  template <typename T>
  CsvWriter& operator<<(const T& value) {
    if (!first_) line_ << ',';
    first_ = false;
    line_ << value;
    return *this;
  }
  /// Ends the current row.
  void endRow();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream file_;
  std::ostringstream line_;
  bool first_ = true;
};

}  // namespace study
