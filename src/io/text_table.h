// Reading the small whitespace-separated text tables of RGB-D datasets (rgb.txt, depth.txt,
// associations.txt, groundtruth.txt, calibration.txt, masks/*.txt) with line numbers, so every
// parse error can name the file and line.
#pragma once

#include <string>
#include <vector>

namespace emf::io {

/// One non-empty, non-comment line of a text table.
struct TableRow {
  int line = 0;                     // 1-based line number in the file
  std::vector<std::string> fields;  // whitespace-separated fields
};

/// Reads `path`, skipping empty lines and lines whose first non-blank character is '#'. Fields
/// are separated by spaces and tabs (and commas when `commas_separate` is true, as the TUM
/// tools accept). CR line ends are tolerated. Throws IoError if the file cannot be read.
std::vector<TableRow> readTable(const std::string& path, bool commas_separate = false);

/// "path:line" for error messages.
std::string fileLine(const std::string& path, int line);

/// Parses a finite double; throws IoError "path:line: <what> 'text' is not a number" otherwise.
/// NaN and infinity are errors too (`what` names the field, e.g. "timestamp").
double parseFinite(const std::string& text, const std::string& path, int line,
                   const std::string& what);

/// Parses an integer; throws IoError naming path:line and `what` otherwise.
long long parseInteger(const std::string& text, const std::string& path, int line,
                       const std::string& what);

/// Throws IoError "path:line: expected <n> fields (<layout>), got <m>" unless the row has
/// exactly `n` fields (or at least `n` when `at_least`).
void expectFields(const TableRow& row, size_t n, const std::string& path, const std::string& layout,
                  bool at_least = false);

}  // namespace emf::io
