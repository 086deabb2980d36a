#include "io/text_table.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/error.h"

namespace emf::io {

std::vector<TableRow> readTable(const std::string& path, bool commas_separate) {
  std::ifstream in(path, std::ios::binary);
  if (std::filesystem::is_directory(path)) {
    throw IoError("'" + path + "' is a folder; a text file is expected there");
  }
  if (!in) throw IoError("cannot open '" + path + "': file missing or unreadable");
  std::vector<TableRow> rows;
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    for (char& c : text) {
      if (c == '\t' || c == '\r' || (commas_separate && c == ',')) c = ' ';
    }
    const size_t first = text.find_first_not_of(' ');
    if (first == std::string::npos || text[first] == '#') continue;
    TableRow row;
    row.line = line;
    std::istringstream fields(text);
    std::string f;
    while (fields >> f) row.fields.push_back(f);
    rows.push_back(std::move(row));
  }
  if (in.bad()) throw IoError("error reading '" + path + "' after line " + std::to_string(line));
  return rows;
}

std::string fileLine(const std::string& path, int line) {
  return path + ":" + std::to_string(line);
}

double parseFinite(const std::string& text, const std::string& path, int line,
                   const std::string& what) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  if (end == begin || *end != '\0') {
    throw IoError(fileLine(path, line) + ": " + what + " '" + text + "' is not a number");
  }
  if (!std::isfinite(v) || errno == ERANGE) {
    throw IoError(fileLine(path, line) + ": " + what + " is '" + text +
                  "' (NaN, infinite or out of range); fix or remove that line");
  }
  return v;
}

long long parseInteger(const std::string& text, const std::string& path, int line,
                       const std::string& what) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(begin, &end, 10);
  if (end == begin || *end != '\0' || errno == ERANGE) {
    throw IoError(fileLine(path, line) + ": " + what + " '" + text + "' is not an integer");
  }
  return v;
}

void expectFields(const TableRow& row, size_t n, const std::string& path, const std::string& layout,
                  bool at_least) {
  const bool ok = at_least ? row.fields.size() >= n : row.fields.size() == n;
  if (!ok) {
    throw IoError(fileLine(path, row.line) + ": expected " + (at_least ? "at least " : "") +
                  std::to_string(n) + " fields (" + layout + "), got " +
                  std::to_string(row.fields.size()));
  }
}

}  // namespace emf::io
