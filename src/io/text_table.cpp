// Text tables of measurements and positions (snl import). Pure string
// processing: the fuzz target tests/fuzz/fuzz_text_table.cpp runs it.
#include "io/text_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace snl::text {

namespace {

constexpr double kMinSigma = 1e-150, kMaxSigma = 1e150;  // the network file's rule (src/io/validate.cpp)

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

// Fields of one line into `out` (reused from line to line: no allocation per row).
void split_fields(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  if (line.find(',') != std::string_view::npos) {
    for (;;) {
      const auto c = line.find(',');
      out.push_back(trim(line.substr(0, c)));
      if (c == std::string_view::npos) break;
      line.remove_prefix(c + 1);
    }
    return;
  }
  std::size_t k = 0;
  while (k < line.size()) {
    while (k < line.size() && is_blank(line[k])) ++k;
    const std::size_t b = k;
    while (k < line.size() && !is_blank(line[k])) ++k;
    if (k > b) out.push_back(line.substr(b, k - b));
  }
}

std::string num(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Inf" : "-Inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string s(std::int64_t v) { return std::to_string(v); }

[[noreturn]] void fail(const std::string& name, std::int64_t line, const std::string& what) {
  throw Error(name + ":" + s(line) + ": " + what);
}

// Every row has as many columns as the first, between lo and hi.
struct ColumnRule {
  const std::string& name;
  int lo, hi;
  const char* layout;    // what the columns are, for the message
  const char* why_same;  // why every row needs the same count
  int cols = 0;          // of the first row (0: no row yet)
  std::int64_t first_line = 0;
  void check(const TextRow& r) {
    const int c = static_cast<int>(r.fields.size());
    if (c < lo || c > hi) fail(name, r.line, s(c) + " columns, expected " + layout);
    if (cols == 0) {
      cols = c;
      first_line = r.line;
    } else if (c != cols) {
      fail(name, r.line, s(c) + " columns, but line " + s(first_line) + " has " + s(cols) + ": " + why_same);
    }
  }
};

double field_number(const TextRow& r, int col, const char* what, const std::string& name) {
  const std::string_view f = r.fields[col];
  if (f.empty()) fail(name, r.line, "column " + s(col + 1) + " (" + what + ") is empty");
  double v = 0;
  if (!parse_double(f, v)) fail(name, r.line, "column " + s(col + 1) + " (" + what + "): " + quoted(f) + " is not a number");
  return v;
}

GlobalId field_id(const TextRow& r, int col, const char* what, const std::string& name, int base) {
  const std::string_view f = r.fields[col];
  if (f.empty()) fail(name, r.line, "column " + s(col + 1) + " (" + what + ") is empty");
  std::int64_t v = 0;
  if (!parse_int(f, v))
    fail(name, r.line, "column " + s(col + 1) + " (" + what + "): " + quoted(f) + " is not an integer index");
  if (v < base)
    fail(name, r.line, std::string(what) + " index " + s(v) + " is below the index base " + s(base) +
                           (base == 1 ? " (--index-base 1)" : ""));
  if (v == std::numeric_limits<std::int64_t>::max()) fail(name, r.line, std::string(what) + " index " + s(v) + " is too large");
  return v - base;
}

// Calls f(row) for each data row of `text` (the rules of split_rows); the
// row's field vector is reused, so a large file costs no allocation per row.
template <class F>
void for_each_row(std::string_view text, F&& f) {
  TextRow r;
  bool first = true;
  while (!text.empty()) {
    const auto nl = text.find('\n');
    std::string_view l = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++r.line;
    if (const auto h = l.find('#'); h != std::string_view::npos) l = l.substr(0, h);
    l = trim(l);
    if (l.empty()) continue;
    split_fields(l, r.fields);
    // A header: the first data line, without a single number (so that a typo
    // in the first row is reported, not skipped as a header).
    const bool header = first && std::none_of(r.fields.begin(), r.fields.end(), [](std::string_view v) {
                          double d = 0;
                          return parse_double(v, d);
                        });
    first = false;
    if (!header) f(static_cast<const TextRow&>(r));
  }
}

}  // namespace

bool parse_double(std::string_view f, double& v) {
  if (!f.empty() && f.front() == '+') f.remove_prefix(1);
  if (f.empty() || f.front() == '+') return false;
  const char* end = f.data() + f.size();
  const auto r = std::from_chars(f.data(), end, v);
  if (r.ptr != end) return false;
  if (r.ec == std::errc::result_out_of_range) {  // under- or overflow: what strtod gives (0 or +-Inf)
    v = std::strtod(std::string(f).c_str(), nullptr);
    return true;
  }
  return r.ec == std::errc();
}

bool parse_int(std::string_view f, std::int64_t& v) {
  if (!f.empty() && f.front() == '+') f.remove_prefix(1);
  if (f.empty() || f.front() == '+') return false;
  const auto r = std::from_chars(f.data(), f.data() + f.size(), v);
  return r.ec == std::errc() && r.ptr == f.data() + f.size();
}

std::string quoted(std::string_view f) {
  constexpr std::size_t kMax = 40;
  return "'" + std::string(f.substr(0, kMax)) + (f.size() > kMax ? "...'" : "'");
}

std::vector<TextRow> split_rows(std::string_view text) {
  std::vector<TextRow> rows;
  for_each_row(text, [&](const TextRow& r) { rows.push_back(r); });
  return rows;
}

EdgeTable parse_edges(std::string_view text, const std::string& name, EdgeKind kind, int index_base) {
  const bool sensor = kind == EdgeKind::kSensor;
  const char* layout = sensor ? "3 or 4 (i, j, range[, sigma])" : "3 or 4 (i, anchor, range[, sigma])";
  ColumnRule rule{name, 3, 4, layout, "a sigma column must be on every row or on none"};
  EdgeTable t;
  for_each_row(text, [&](const TextRow& r) {
    rule.check(r);
    const GlobalId i = field_id(r, 0, "sensor", name, index_base);
    const GlobalId j = field_id(r, 1, sensor ? "sensor" : "anchor", name, index_base);
    if (sensor && i == j) fail(name, r.line, "self-loop (" + s(i + index_base) + ", " + s(j + index_base) + ")");
    const double d = field_number(r, 2, "range", name);
    if (!std::isfinite(d)) fail(name, r.line, "range is " + num(d));
    if (d < 0) fail(name, r.line, "range " + num(d) + " is negative");
    if (rule.cols == 4) {
      const double sg = field_number(r, 3, "sigma", name);
      if (!(sg >= kMinSigma && sg <= kMaxSigma))
        fail(name, r.line, "sigma " + num(sg) + " is outside [1e-150, 1e150] (weights 1/sigma^2 must be finite and positive)");
      t.sigmas.push_back(sg);
    }
    t.edges.push_back(i);
    t.edges.push_back(j);
    t.ranges.push_back(d);
    t.lines.push_back(r.line);
  });
  return t;
}

PointTable parse_points(std::string_view text, const std::string& name) {
  ColumnRule rule{name, 1, 3, "1, 2 or 3 coordinates (the dimension p)",
                  "every row must have the same number of coordinates (the dimension p)"};
  PointTable t;
  static const char* const kAxis[] = {"x", "y", "z"};
  for_each_row(text, [&](const TextRow& r) {
    rule.check(r);
    for (int c = 0; c < rule.cols; ++c) {
      const double v = field_number(r, c, kAxis[c], name);
      if (!std::isfinite(v)) fail(name, r.line, "coordinate " + std::string(kAxis[c]) + " is " + num(v));
      t.coords.push_back(v);
    }
    t.lines.push_back(r.line);
  });
  t.dim = rule.cols;
  return t;
}

std::string ImportOptions::validate() const {
  if (sensors < 0) return "--sensors must be positive, got " + s(sensors);
  if (index_base != 0 && index_base != 1) return "--index-base must be 0 or 1, got " + s(index_base);
  if (!(sigma < 0) && !(std::isfinite(sigma) && sigma >= 0)) return "--sigma must be finite and >= 0";
  return {};
}

namespace {

// n from the options, the truth file or the largest sensor id (ImportOptions::sensors).
GlobalId decide_sensors(const EdgeTable& se, const EdgeTable& ae, const std::optional<PointTable>& truth,
                        const ImportInput& in, const ImportOptions& opt) {
  if (opt.sensors > 0) return opt.sensors;
  if (truth) {
    if (truth->rows() == 0) throw Error(in.truth->name + ": no rows (one true position per sensor expected)");
    return truth->rows();
  }
  GlobalId top = -1;
  for (GlobalId v : se.edges) top = std::max(top, v);
  for (std::size_t e = 0; e < ae.edges.size(); e += 2) top = std::max(top, ae.edges[e]);
  if (top < 0)
    throw Error("no sensor ids in " + in.sensor_edges.name + " or " + in.anchor_edges.name +
                ": give the number of sensors (--sensors N) or a truth file");
  return top + 1;
}

// Every id of `t` (column `col` of each pair, or both when col < 0) below `limit`.
void check_ids(const EdgeTable& t, int col, GlobalId limit, int base, const std::string& name, const char* what,
               const std::string& why) {
  for (std::size_t e = 0; e < t.lines.size(); ++e)
    for (int c = 0; c < 2; ++c) {
      if (col >= 0 && c != col) continue;
      const GlobalId v = t.edges[2 * e + c];
      if (v >= limit)
        fail(name, t.lines[e], std::string(what) + " index " + s(v + base) + " out of range [" + s(base) + ", " +
                                   s(limit + base) + ") (" + why + ")");
    }
}

}  // namespace

Network import_network(const ImportInput& in, const ImportOptions& opt) {
  if (const std::string bad = opt.validate(); !bad.empty()) throw Error(bad);
  const int base = opt.index_base;
  EdgeTable se = parse_edges(in.sensor_edges.text, in.sensor_edges.name, EdgeKind::kSensor, base);
  EdgeTable ae = parse_edges(in.anchor_edges.text, in.anchor_edges.name, EdgeKind::kAnchor, base);
  PointTable anchors = parse_points(in.anchors.text, in.anchors.name);
  if (anchors.rows() == 0)
    throw Error(in.anchors.name + ": no anchor rows (at least one anchor is needed; its columns give the dimension p)");
  std::optional<PointTable> truth;
  if (in.truth) {
    truth = parse_points(in.truth->text, in.truth->name);
    if (truth->rows() > 0 && truth->dim != anchors.dim)
      fail(in.truth->name, truth->lines.front(), s(truth->dim) + " coordinates, but " + in.anchors.name + " has " +
                                                     s(anchors.dim) + " (the dimension p)");
  }
  const GlobalId n = decide_sensors(se, ae, truth, in, opt);
  const std::string why_n = opt.sensors > 0 ? "n = " + s(n) + " from --sensors"
                            : truth         ? "n = " + s(n) + " rows in " + in.truth->name
                                            : "n = largest sensor id + 1";
  if (truth && truth->rows() != n)
    throw Error(in.truth->name + ": " + s(truth->rows()) + " rows, expected one per sensor (" + why_n + ")");
  check_ids(se, -1, n, base, in.sensor_edges.name, "sensor", why_n);
  check_ids(ae, 0, n, base, in.anchor_edges.name, "sensor", why_n);
  check_ids(ae, 1, anchors.rows(), base, in.anchor_edges.name, "anchor",
            s(anchors.rows()) + " rows in " + in.anchors.name);

  Network net;
  net.dim = anchors.dim;
  net.num_sensors = n;
  net.anchors = std::move(anchors.coords);
  net.sensor_edges = std::move(se.edges);
  net.sensor_ranges = std::move(se.ranges);
  net.sensor_sigmas = std::move(se.sigmas);
  net.anchor_edges = std::move(ae.edges);
  net.anchor_ranges = std::move(ae.ranges);
  net.anchor_sigmas = std::move(ae.sigmas);
  if (truth) {
    net.has_truth = true;
    net.truth = std::move(truth->coords);
  }
  if (opt.sigma >= 0) net.sigma = opt.sigma;
  net.total_sensor_edges = net.local_sensor_edges();
  net.total_anchor_edges = net.local_anchor_edges();
  return net;
}

}  // namespace snl::text
