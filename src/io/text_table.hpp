#pragma once
// Text tables of measurements and positions, the input of `snl import`
// (docs/formats.md, "Text files"): CSV or whitespace-separated rows, '#'
// comments, an optional header line. Pure functions on strings: no MPI, no
// files (a fuzz target). Every error is an snl::Error "NAME:LINE: what".
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "snl/io/network.hpp"

namespace snl::text {

/// The fields of one data line, and its 1-based line number.
struct TextRow {
  std::int64_t line = 0;
  std::vector<std::string_view> fields;
};

/// A whole field as an integer / a number ('+' allowed once; no trailing
/// text); a double out of range reads as strtod's 0 or +-Inf.
bool parse_int(std::string_view field, std::int64_t& v);
bool parse_double(std::string_view field, double& v);
/// The field in quotes, cut at 40 characters, for messages.
std::string quoted(std::string_view field);

/// Splits `text` into data rows: '#' starts a comment, blank lines are
/// skipped, a line with a comma is split at commas (fields trimmed), any
/// other at runs of blanks. The first data line is a header, and skipped,
/// when its first field is not a number. Views point into `text`.
std::vector<TextRow> split_rows(std::string_view text);

enum class EdgeKind { kSensor, kAnchor };

/// Rows "i,j,range[,sigma]" (kSensor) or "i,anchor,range[,sigma]" (kAnchor).
struct EdgeTable {
  std::vector<GlobalId> edges;      ///< [2 * rows] the two ids, index base removed
  std::vector<double> ranges;       ///< [rows]
  std::vector<double> sigmas;       ///< [rows], or empty when there is no sigma column
  std::vector<std::int64_t> lines;  ///< [rows] line of each row in the file
};

/// Checks each row on its own: 3 or 4 columns (the same on every row),
/// integer ids >= index_base, a finite range >= 0, a sigma in [1e-150, 1e150]
/// (the network file's rule), no self-loop for sensor pairs.
EdgeTable parse_edges(std::string_view text, const std::string& name, EdgeKind kind, int index_base);

/// Rows of p = 1, 2 or 3 finite coordinates (anchors, truth), p the same on every row.
struct PointTable {
  int dim = 0;                      ///< columns; 0 when the file has no rows
  std::vector<double> coords;       ///< [rows * dim]
  std::vector<std::int64_t> lines;  ///< [rows]
  GlobalId rows() const { return static_cast<GlobalId>(lines.size()); }
};
PointTable parse_points(std::string_view text, const std::string& name);

/// A text file by the name errors give it (the path as typed) and its content.
struct TextFile {
  std::string name;
  std::string text;
};

struct ImportInput {
  TextFile sensor_edges, anchor_edges, anchors;
  std::optional<TextFile> truth;
};

struct ImportOptions {
  /// n. 0: the number of truth rows when a truth file is given, else the
  /// largest sensor id in the edge files + 1 (in 0-based ids).
  GlobalId sensors = 0;
  int index_base = 0;  ///< ids in the files (sensors and anchors) start at 0 or 1
  double sigma = -1;   ///< network noise standard deviation to record (< 0: unknown)
  std::string validate() const;
};

/// The whole network of the four tables, with the index-range and shape
/// checks that need all of them (ids < n and < m, one dimension, n truth
/// rows), each reported at its line. Rows are kept in file order; duplicates
/// stay (the network reader merges them). A returned network passes
/// check_network(net, true).
Network import_network(const ImportInput& in, const ImportOptions& opt);

}  // namespace snl::text
