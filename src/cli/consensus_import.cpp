// `snl consensus import`: a consensus problem file (docs/consensus.md) from two
// CSV tables, samples (node id, features, label or target) and links (two node
// ids), built and checked on rank 0. Every error names the file and its line.
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "cli/cli_util.hpp"
#include "io/text_table.hpp"
#include "snl/cli/commands.hpp"
#include "snl/cli/consensus.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl {

namespace {

using detail::read_text_file;
using text::parse_double;
using text::parse_int;
using text::quoted;

constexpr GlobalId kMaxNodes = 2147483647;  // the format's limit (problem_detail.hpp)
constexpr int kMaxDim = 4096;

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

/// One non-blank, non-comment line of a CSV file: its 1-based number and its
/// comma-separated fields (trimmed; no quoting).
struct CsvRow {
  std::int64_t line = 0;
  std::vector<std::string_view> fields;
};

std::vector<CsvRow> csv_rows(std::string_view text) {
  std::vector<CsvRow> rows;
  std::int64_t line = 0;
  while (!text.empty()) {
    const auto nl = text.find('\n');
    std::string_view l = trim(text.substr(0, nl));
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line;
    if (l.empty() || l.front() == '#') continue;
    CsvRow r;
    r.line = line;
    for (;;) {
      const auto c = l.find(',');
      r.fields.push_back(trim(l.substr(0, c)));
      if (c == std::string_view::npos) break;
      l.remove_prefix(c + 1);
    }
    rows.push_back(std::move(r));
  }
  return rows;
}

[[noreturn]] void fail(const std::string& file, std::int64_t line, const std::string& what) {
  throw Error(file + ":" + std::to_string(line) + ": " + what);
}


/// Column `col` of row r as a node id: an integer >= 0 and < nodes (when nodes > 0).
GlobalId node_id(const std::string& file, const CsvRow& r, std::size_t col, const std::string& what, GlobalId nodes) {
  const std::string_view f = r.fields[col];
  const std::string where = "column " + std::to_string(col + 1) + " (" + what + ")";
  std::int64_t v = 0;
  if (f.empty()) fail(file, r.line, where + " is empty");
  if (!parse_int(f, v)) fail(file, r.line, where + ": " + quoted(f) + " is not an integer node id");
  if (v < 0) fail(file, r.line, where + ": node id " + std::to_string(v) + " is negative (ids start at 0)");
  if (nodes > 0 && v >= nodes)
    fail(file, r.line, where + ": node id " + std::to_string(v) + " out of range [0, " + std::to_string(nodes) +
                           ") (--nodes " + std::to_string(nodes) + ")");
  if (v >= kMaxNodes)
    fail(file, r.line, where + ": node id " + std::to_string(v) + " too large (at most " +
                           std::to_string(kMaxNodes - 1) + ")");
  return v;
}

double finite_number(const std::string& file, const CsvRow& r, std::size_t col, const std::string& name) {
  const std::string_view f = r.fields[col];
  const std::string where = "column " + std::to_string(col + 1) + " ('" + name + "')";
  double v = 0;
  if (f.empty()) fail(file, r.line, where + " is empty");
  if (!parse_double(f, v)) fail(file, r.line, where + ": " + quoted(f) + " is not a number");
  if (!std::isfinite(v)) fail(file, r.line, where + ": " + quoted(f) + " is not a finite number");
  return v;
}

/// The column named `name` in the header ("" = `fallback`).
std::size_t column_of(const std::string& file, const CsvRow& header, const std::string& name, std::size_t fallback,
                      const char* option) {
  if (name.empty()) return fallback;
  for (std::size_t c = 0; c < header.fields.size(); ++c)
    if (header.fields[c] == name) return c;
  std::string names;
  for (std::size_t c = 0; c < header.fields.size(); ++c) names += (c ? ", '" : "'") + std::string(header.fields[c]) + "'";
  throw UsageError(file + ":" + std::to_string(header.line) + ": " + option + " '" + name +
                   "' names no column of the header (columns: " + names + ")");
}

struct Imported {
  consensus::ProblemData data;
  GlobalId nodes_without_samples = 0;
  std::string node_column, label_column;
};

/// Samples: header, then rows of node id, features, label (any column order).
void read_samples(const ConsensusImportCommand& cmd, const std::string& text, Imported& out) {
  const std::string& file = cmd.samples;
  consensus::ProblemData& d = out.data;
  const std::vector<CsvRow> rows = csv_rows(text);
  if (rows.empty()) throw Error(file + ": no header line (the first line names the columns: node, features, label)");
  const CsvRow& header = rows.front();
  const std::size_t C = header.fields.size();
  for (std::size_t c = 0; c < C; ++c) {
    if (header.fields[c].empty())
      fail(file, header.line, "header: column " + std::to_string(c + 1) + " has no name");
    for (std::size_t k = 0; k < c; ++k)
      if (header.fields[k] == header.fields[c])
        fail(file, header.line, "header: column name '" + std::string(header.fields[c]) + "' appears twice (columns " +
                                    std::to_string(k + 1) + " and " + std::to_string(c + 1) + ")");
  }
  if (C < 3)
    fail(file, header.line, "header has " + std::to_string(C) +
                                " columns, expected at least 3 (a node id, one or more features, a label)");
  const std::size_t node_col = column_of(file, header, cmd.node_column, 0, "--node-column");
  const std::size_t label_col = column_of(file, header, cmd.label_column, C - 1, "--label-column");
  if (node_col == label_col)
    throw UsageError(file + ": the node column and the label column are both column " + std::to_string(node_col + 1) +
                     " ('" + std::string(header.fields[node_col]) + "'); give --node-column and --label-column");
  out.node_column = header.fields[node_col];
  out.label_column = header.fields[label_col];
  std::vector<std::size_t> feature_cols;
  for (std::size_t c = 0; c < C; ++c)
    if (c != node_col && c != label_col) feature_cols.push_back(c);
  const int q = static_cast<int>(feature_cols.size());
  if (q > kMaxDim) fail(file, header.line, std::to_string(q) + " feature columns, at most " + std::to_string(kMaxDim));
  d.dim = q;
  if (rows.size() < 2) fail(file, header.line, "header but no samples");
  const bool logistic = d.family == consensus::Family::kLogistic;
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const CsvRow& r = rows[k];
    if (r.fields.size() != C)
      fail(file, r.line, std::to_string(r.fields.size()) + " columns, but the header (line " +
                             std::to_string(header.line) + ") has " + std::to_string(C));
    d.owner.push_back(node_id(file, r, node_col, "'" + out.node_column + "', the node id", cmd.nodes));
    for (const std::size_t c : feature_cols) d.features.push_back(finite_number(file, r, c, std::string(header.fields[c])));
    const double y = finite_number(file, r, label_col, out.label_column);
    if (logistic && y != 1.0 && y != -1.0)
      fail(file, r.line, "column " + std::to_string(label_col + 1) + " ('" + out.label_column + "'): " +
                             quoted(r.fields[label_col]) + " is not +1 or -1 (family logistic)");
    d.labels.push_back(y);
  }
}

/// Links: an optional header, then rows of two node ids; no self-loop, each link once.
void read_edges(const ConsensusImportCommand& cmd, const std::string& text, consensus::ProblemData& d) {
  const std::string& file = cmd.edges;
  std::vector<CsvRow> rows = csv_rows(text);
  std::int64_t probe = 0;
  if (!rows.empty() && !parse_int(rows.front().fields.front(), probe)) rows.erase(rows.begin());  // a header
  std::map<std::pair<GlobalId, GlobalId>, std::int64_t> seen;  // link -> its line
  for (const CsvRow& r : rows) {
    if (r.fields.size() != 2)
      fail(file, r.line, std::to_string(r.fields.size()) + " columns, expected 2 (the node ids of a link)");
    const GlobalId i = node_id(file, r, 0, "first node", cmd.nodes), j = node_id(file, r, 1, "second node", cmd.nodes);
    if (i == j) fail(file, r.line, "self-loop (" + std::to_string(i) + ", " + std::to_string(j) + ")");
    const auto key = std::make_pair(std::min(i, j), std::max(i, j));
    const auto [it, fresh] = seen.emplace(key, r.line);
    if (!fresh)
      fail(file, r.line, "link (" + std::to_string(key.first) + ", " + std::to_string(key.second) +
                             ") repeats line " + std::to_string(it->second) +
                             " (each undirected link must be listed once)");
    d.edges.push_back(i);
    d.edges.push_back(j);
  }
}

/// Connected, or the message naming a node that node 0 cannot reach.
void check_connected(const std::string& file, const consensus::ProblemData& d) {
  const GlobalId n = d.num_nodes, E = static_cast<GlobalId>(d.edges.size() / 2);
  if (E < n - 1)
    throw Error(file + ": the graph is not connected (" + std::to_string(E) + " links for " + std::to_string(n) +
                " nodes, at least " + std::to_string(n - 1) + " needed): consensus is undefined on a disconnected "
                "network");
  std::vector<GlobalId> root(static_cast<std::size_t>(n));
  std::iota(root.begin(), root.end(), GlobalId{0});
  const auto find = [&](GlobalId v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  for (GlobalId e = 0; e < E; ++e) {
    const GlobalId a = find(d.edges[2 * e]), b = find(d.edges[2 * e + 1]);
    if (a != b) root[std::max(a, b)] = std::min(a, b);
  }
  for (GlobalId v = 1; v < n; ++v)
    if (find(v) != find(0))
      throw Error(file + ": the graph is not connected (node " + std::to_string(v) +
                  " cannot be reached from node 0): consensus is undefined on a disconnected network");
}

Imported import_problem(const ConsensusImportCommand& cmd) {
  Imported out;
  consensus::ProblemData& d = out.data;
  d.family = consensus::parse_family(cmd.family);
  d.lambda = cmd.lambda;
  const std::string samples = read_text_file(cmd.samples), edges = read_text_file(cmd.edges);
  read_samples(cmd, samples, out);
  read_edges(cmd, edges, d);
  GlobalId n = cmd.nodes;
  if (n == 0) {
    for (GlobalId v : d.owner) n = std::max(n, v + 1);
    for (GlobalId v : d.edges) n = std::max(n, v + 1);
    if (n < 2)
      throw Error(cmd.samples + ", " + cmd.edges + ": the largest node id is " + std::to_string(n - 1) +
                  ": consensus needs at least 2 nodes");
  }
  d.num_nodes = n;
  check_connected(cmd.edges, d);
  std::vector<char> has(static_cast<std::size_t>(n), 0);
  for (GlobalId v : d.owner) has[v] = 1;
  out.nodes_without_samples = static_cast<GlobalId>(std::count(has.begin(), has.end(), 0));
  // The format's remaining rules (f_p finite at x = 0, ...), all others checked above with their lines.
  try {
    consensus::validate_problem(d);
  } catch (const Error& e) {
    throw Error(cmd.samples + ": " + e.what());
  }
  return out;
}

void validate_options(const ConsensusImportCommand& cmd) {
  if (cmd.family != "logistic" && cmd.family != "least_squares")
    throw UsageError("--family must be logistic or least_squares (got '" + cmd.family + "')");
  if (!std::isfinite(cmd.lambda) || !(cmd.lambda > 0))
    throw UsageError("--lambda must be a finite number > 0 (got " + std::to_string(cmd.lambda) + ")");
  if (cmd.nodes != 0 && (cmd.nodes < 2 || cmd.nodes > kMaxNodes))
    throw UsageError("--nodes must be in [2, " + std::to_string(kMaxNodes) + "] (got " + std::to_string(cmd.nodes) +
                     ")");
}

}  // namespace

void run_consensus_import(const ConsensusImportCommand& cmd, MPI_Comm comm) {
  validate_options(cmd);
  check_output_path(cmd.output, comm, {{"--samples", cmd.samples}, {"--edges", cmd.edges}});
  std::string summary, usage;
  collective_try(comm, [&] {
    if (comm_rank(comm) != 0) return;
    Imported im;
    try {
      im = import_problem(cmd);
    } catch (const UsageError& e) {  // an option that does not fit the files (a column name): status 2
      usage = e.what();
      return;
    }
    consensus::write_problem(MPI_COMM_SELF, cmd.output, im.data);
    const consensus::ProblemData& d = im.data;
    std::ostringstream os;
    os << "imported " << cmd.output << ": n=" << d.num_nodes << ", " << d.edges.size() / 2 << " links, family "
       << consensus::family_name(d.family) << ", dim " << d.dim << " (node column '" << im.node_column
       << "', label column '" << im.label_column << "'), " << d.num_samples() << " samples, lambda " << d.lambda;
    if (im.nodes_without_samples > 0)
      os << "\nnote: " << im.nodes_without_samples << " of " << d.num_nodes
         << " nodes own no sample (their f_p is the regulariser alone)";
    summary = os.str();
  });
  usage = bcast_string(comm, usage);
  if (!usage.empty()) throw UsageError(usage);
  if (comm_rank(comm) == 0 && !cmd.quiet) std::printf("%s\n", summary.c_str());
}

}  // namespace snl
