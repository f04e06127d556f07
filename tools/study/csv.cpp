#include "csv.hpp"

#include <iomanip>
#include <limits>
#include <stdexcept>

namespace study {

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& columns) : path_(path), file_(path) {
  if (!file_) throw std::runtime_error("cannot write " + path);
  line_ << std::setprecision(std::numeric_limits<double>::max_digits10 - 2);
  for (const std::string& c : columns) *this << c;
  endRow();
}

void CsvWriter::endRow() {
  file_ << line_.str() << '\n';
  line_.str(std::string());
  first_ = true;
  if (!file_) throw std::runtime_error("write failed: " + path_);
}

}  // namespace study
