// The measurement model (weights.hpp): parsing --weights / --loss and the
// per-measurement weights of a LocalizationProblem.
#include "snl/problem/weights.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "snl/core/common.hpp"
#include "snl/problem/problem.hpp"

namespace snl {

namespace {

// A finite number > 0 spelled out in full ("" or trailing text: NaN).
double positive_number(const std::string& s) {
  if (s.empty()) return NAN;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || !std::isfinite(v) || !(v > 0)) return NAN;
  return v;
}

// Ranges below this fraction of the largest range take sigma as if at it
// (multiplicative weights): a zero range would otherwise get an infinite weight.
constexpr double kRangeFloor = 1e-2;

double max_all(MPI_Comm comm, double v) {
  double g = 0;
  MPI_Allreduce(&v, &g, 1, MPI_DOUBLE, MPI_MAX, comm);
  return g;
}
double min_all(MPI_Comm comm, double v) {
  double g = 0;
  MPI_Allreduce(&v, &g, 1, MPI_DOUBLE, MPI_MIN, comm);
  return g;
}

}  // namespace

WeightsSpec parse_weights_spec(const std::string& s) {
  WeightsSpec w;
  const std::string pre = "multiplicative:";
  if (s == "auto") return w;
  if (s == "file") {
    w.kind = WeightsSpec::Kind::kFile;
  } else if (s == "none") {
    w.kind = WeightsSpec::Kind::kNone;
  } else if (s.compare(0, pre.size(), pre) == 0 && std::isfinite(positive_number(s.substr(pre.size())))) {
    w.kind = WeightsSpec::Kind::kMultiplicative;
    w.factor = positive_number(s.substr(pre.size()));
  } else {
    throw Error("bad --weights '" + s + "' (expected file, none or multiplicative:NF with NF > 0)");
  }
  return w;
}

double parse_loss_spec(const std::string& s) {
  const std::string pre = "huber:";
  if (s == "l2") return 0.0;
  if (s.compare(0, pre.size(), pre) == 0) {
    const double d = positive_number(s.substr(pre.size()));
    if (std::isfinite(d)) return d;
  }
  throw Error("bad --loss '" + s + "' (expected l2 or huber:DELTA with DELTA > 0)");
}

// Sigmas per slot and per anchor measurement (from the file or from the
// ranges), then w = (sigma_min / sigma)^2 with sigma_min over the network.
void LocalizationProblem::set_measurement_model(const WeightsSpec& spec, double huber_delta) {
  MPI_Comm comm = this->comm();
  model_ = MeasurementModel();
  model_.huber_delta = huber_delta;
  WeightsSpec::Kind kind = spec.kind;
  // A side without per-measurement sigmas takes the network's sigma; without
  // that, file weights are incomplete: refused when asked for, none for auto.
  const bool complete = (has_sensor_sigmas_ || sigma_) && (has_anchor_sigmas_ || sigma_);
  if (kind == WeightsSpec::Kind::kAuto)
    kind = (has_sensor_sigmas_ || has_anchor_sigmas_) && complete ? WeightsSpec::Kind::kFile : WeightsSpec::Kind::kNone;
  const std::size_t ns = graph_.adjacency().size(), na = anchor_ranges_.size();
  std::vector<double> ss, as;
  if (kind == WeightsSpec::Kind::kFile) {
    if (!has_sensor_sigmas_ && !has_anchor_sigmas_)
      throw Error("--weights file: the network has no sensor_sigmas/anchor_sigmas datasets");
    if (!complete)
      throw Error(std::string("--weights file: the network has ") +
                  (has_sensor_sigmas_ ? "sensor_sigmas but no anchor_sigmas" : "anchor_sigmas but no sensor_sigmas") +
                  " and no network sigma to stand in for them");
    ss = has_sensor_sigmas_ ? sensor_sigmas_ : std::vector<double>(ns, *sigma_);
    as = has_anchor_sigmas_ ? anchor_sigmas_ : std::vector<double>(na, *sigma_);
  } else if (kind == WeightsSpec::Kind::kMultiplicative) {
    double rmax = 0;
    for (std::size_t e = 0; e < ns; ++e) rmax = std::max(rmax, graph_.edge_value(std::int64_t(e)));
    for (double r : anchor_ranges_) rmax = std::max(rmax, r);
    rmax = max_all(comm, rmax);
    const double floor = rmax > 0 ? kRangeFloor * rmax : 1.0;
    ss.resize(ns);
    as.resize(na);
    for (std::size_t e = 0; e < ns; ++e) ss[e] = spec.factor * std::max(graph_.edge_value(std::int64_t(e)), floor);
    for (std::size_t e = 0; e < na; ++e) as[e] = spec.factor * std::max(anchor_ranges_[e], floor);
  }
  if (kind == WeightsSpec::Kind::kNone) {
    model_.max_weight_sum = graph_.max_degree();
    model_.max_anchor_weight_sum = max_anchor_deg_;
    return;
  }
  double smin = INFINITY;
  for (double s : ss) smin = std::min(smin, s);
  for (double s : as) smin = std::min(smin, s);
  smin = min_all(comm, smin);
  model_.weighted = true;
  model_.edge_weights.resize(ns);
  model_.anchor_weights.resize(na);
  for (std::size_t e = 0; e < ns; ++e) model_.edge_weights[e] = (smin / ss[e]) * (smin / ss[e]);
  for (std::size_t e = 0; e < na; ++e) model_.anchor_weights[e] = (smin / as[e]) * (smin / as[e]);
  // Lipschitz sums, each node's slots in slot (global-id) order: the same on any partition.
  double ws = 0, wa = 0;
  const auto& off = graph_.offsets();
  for (LocalId v = 0; v < graph_.num_owned(); ++v) {
    double s = 0, a = 0;
    for (auto e = off[v]; e < off[v + 1]; ++e) s += model_.edge_weights[e];
    for (auto e = anchor_offsets_[v]; e < anchor_offsets_[v + 1]; ++e) a += model_.anchor_weights[e];
    ws = std::max(ws, s);
    wa = std::max(wa, a);
  }
  model_.max_weight_sum = max_all(comm, ws);
  model_.max_anchor_weight_sum = max_all(comm, wa);
}

}  // namespace snl
